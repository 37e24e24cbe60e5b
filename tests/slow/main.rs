//! The slow tier: whole `neurarm paper` runs and the random-arm family. `scripts/test` runs it;
//! `cargo test --test it` skips it while working.

mod experiments;
mod family;
mod quality;
