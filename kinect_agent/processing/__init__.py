"""Signal processing on recordings: outlier removal, kinematics, UKF, joint angles."""
