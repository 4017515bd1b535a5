"""Pure numpy metrics of one exercise session (no database, no HTTP): repetitions, ranges, workspace, activity.

Every function takes arrays with documented shape and units (times in seconds, positions in metres in the
Kinect camera frame with y up, angles in degrees as kinect_agent.body.angles defines them).
report.analyze_recording assembles the JSON document stored with each session.
"""
