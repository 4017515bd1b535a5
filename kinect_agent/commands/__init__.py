"""Subcommands of `kinect-agent`, one module each (see kinect_agent.cli)."""
