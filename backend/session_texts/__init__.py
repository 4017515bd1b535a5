"""A session's analysis written for a reader: the reasons, the data quality, the camera advice and the session page's
data in the reader's language (reasons, data_quality, camera_advice, session_detail), `coach-server analyze`'s summary
(summary), and the bound of the work an upload may cause (work_budget). The analysis itself (the metrics, the document
and its indicators, the exercises' specs) is kinect_agent.analysis, which the agent ships.
"""
