//! One integration binary: each test runs the real `groombake` executable in
//! a temporary directory (see `util.rs`). Modules group tests by area.

// A test binary: a panic with its message is how a helper reports failure.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod util;

mod alembic;
mod bake;
mod batch;
mod bench;
mod cli;
mod diff;
mod formats;
mod golden;
mod guides;
mod hardening;
mod inspect;
mod install;
mod limits;
mod preview;
mod refusals;
mod roundtrip;
mod samples;
mod usd;
