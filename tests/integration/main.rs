//! One integration binary: each test runs the real `groombake` executable in
//! a temporary directory (see `util.rs`). Modules group tests by area.

// A test binary: a panic with its message is how a helper reports failure.
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod util;

mod alembic;
mod bake;
mod batch;
mod batch_resume;
mod bench;
mod blow_dry_head;
mod cli;
mod diff;
mod formats;
mod generate_head;
mod golden;
mod guard_rails;
mod guide_cache;
mod guides;
mod hairstyle;
mod hardening;
mod hold;
mod inspect;
mod install;
mod limits;
mod preview;
mod readme;
mod refusals;
mod reports;
mod roundtrip;
mod samples;
mod silent_loss;
mod streaming;
mod studio;
mod treatments;
mod usd;
mod usd_structure;
mod usd_time;
mod wind_head;
