//! Subcommands of the `voxbrick` binary, one file each as they move out of main.rs.

pub mod bench_viewport;
