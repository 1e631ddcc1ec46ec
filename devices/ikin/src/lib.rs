//! iCub kinematics (iKin equivalent).
