"""The server's side of a session's analysis: report.analyze_recording assembles the JSON document stored with each
session for an exercise of the server's library (indicators: its headline numbers), and the rest writes it for a
reader (reasons, data_quality, camera_advice, session_detail) or bounds the work an upload may cause (work_budget).
The metrics themselves (pure numpy/scipy, no server imports) live in kinect_agent.analysis, which the agent ships.
"""
