//! One integration binary: each test runs the real `groombake` executable in
//! a temporary directory (see `util.rs`). Modules group tests by area.

// Helpers outside #[test] functions may panic too: this is test code.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod util;

mod cli;
mod usd;
