//! The groombake engine: procedural grooms, the hair simulation, timelines
//! of treatments and previews. The command line in `main.rs` only composes
//! these.

pub mod batch;
pub mod bench;
pub mod budget;
pub mod diff;
pub mod generate;
pub mod preview;
pub mod report_html;
pub mod sim;
pub mod stochastic_wind;
pub mod timeline;
