//! gait-control: the real-time controller, generic over embedded-hal 1.0 so
//! the same code runs on the motor board, under QEMU and in host tests.
#![no_std]
