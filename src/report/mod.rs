//! Reports on runs: figures (PNG) of simulated and learned signals.

pub mod plot;
