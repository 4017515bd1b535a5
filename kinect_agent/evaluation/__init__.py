"""The accuracy study as a tool (`kinect-agent evaluate`): a Kinect recording against simultaneous motion capture.

align (time offset by speed cross-correlation), register (rigid transform), pairs (one aligned pair or its
refusal), measure (errors raw, after outlier removal, after the pipeline), error_parts (bias and random parts),
tables (the paper's tables 1-5), figures (figures 3 and 4), report (Markdown + JSON).
"""
