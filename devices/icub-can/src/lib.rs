//! The iCub CAN protocol and CAN bus backends.
