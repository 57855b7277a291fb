//! End-to-end tests of voxbrick live in `tests/tests/` (commands and history) and
//! `tests/scripts/` (replay scripts run by `tests/tests/replay.rs`).
