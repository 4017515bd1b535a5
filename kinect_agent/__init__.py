"""Kinect Home Coach home agent: capture, clean, filter, queue and upload skeleton sessions."""

__version__ = "0.1.0"
