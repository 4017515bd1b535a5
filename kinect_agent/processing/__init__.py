"""Signal processing on recordings: outlier removal, the UKF and its smoother, the pipeline (the body geometry they
build on: kinect_agent.body)."""
