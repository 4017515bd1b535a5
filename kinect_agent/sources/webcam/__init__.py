"""Camera-only capture: BlazePose landmarks (browser page or the agent's Python runtime) -> the 20-joint skeleton.

- landmarks.py: the wire contract (LandmarkBatch, parse_batch) both sides use;
- mapping.py: 33 landmarks -> 20 joints in the Kinect camera frame, depth by a pinhole model, states from visibility;
- header.py: webcam_header, the session header (device model, hash, runtime, fps achieved) both sides write;
- source.py: WebcamSource, the agent's camera or video source (imports mediapipe only when opened).
"""
