//! One test per row of the fault table in `docs/safety.md` (code,
//! reaction, detection bound, not before), by the part the fault is in.

mod ankles;
mod crutches;
mod drive_current;
mod encoders;
mod inputs;
mod joints;
mod motors;
