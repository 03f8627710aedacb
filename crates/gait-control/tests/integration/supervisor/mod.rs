//! The safety supervisor, driven with synthetic inputs (`support.rs`).

mod nan;
mod operation;
mod rows;
mod support;
