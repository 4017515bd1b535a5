"""Camera sets: a patient records a set with the browser's own camera; only landmarks reach the server.

The page runs the pose landmarker on the patient's device and posts batches of landmarks (never images) for a set
the server started. The server keeps the batches, runs the online filter and the live count on them (the same
live progress as a home agent's set) and, at the set's end, the full offline pipeline with the webcam's settings;
it stores the result once as a normal session of device `webcam`. docs/camera-sets.md describes the design.
"""
