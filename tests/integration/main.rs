//! One integration binary: each test runs the real `groombake` executable in
//! a temporary directory (see `util.rs`). Modules group tests by area.

mod util;

mod bench;
mod cli;
