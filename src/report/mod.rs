//! Reports and plots: spectrum and IES plots, accuracy-vs-time and scaling reports.
pub mod accuracy;
pub mod lights;
pub mod plot;
pub mod render_bench;
