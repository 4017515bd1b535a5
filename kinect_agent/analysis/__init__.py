"""Session analysis (pure numpy/scipy, no database, no HTTP, no server imports): the repetition counter shared by the
agent's live count and the server's session report, and every metric of one recording (angles, intervals, range of
motion, reachable range, activity, balance, sit-to-stand, quality, MDC). Every function takes arrays with
documented shape and units (times in seconds, positions in metres in the Kinect camera frame with y up, angles in
degrees as kinect_agent.body.angles defines them)."""
