//! The scenarios of `editor_handlers.rs`, by subject, and the session they drive.

pub mod basics;
pub mod objects;
pub mod selecting;
pub mod session;
pub mod tools;
