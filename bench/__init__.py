"""Benchmarks of the Kinect Home Coach signal pipeline (run as scripts; they print their numbers)."""
