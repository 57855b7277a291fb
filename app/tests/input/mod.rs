//! The window tests' harness (`editor_input.rs`): the session and screenshots.

pub mod session;
pub mod shot;
