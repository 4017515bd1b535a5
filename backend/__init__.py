"""Kinect Home Coach coaching server: accounts, patients, plans, sessions and suggestions over a REST API."""

__version__ = "0.1.0"
