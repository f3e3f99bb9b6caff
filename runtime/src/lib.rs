//! The robot world (kinematics, collision, simulator, networks, smoothing, drivers): filled by the next issues.
