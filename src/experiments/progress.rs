//! How a run shows how far it has come: the experiments report stages and their steps to a
//! [`Progress`]; the command line draws them as bars, a library user or a test may ignore
//! them ([`NoProgress`]).

/// Where a run reports its progress: one stage at a time, each of a known number of steps.
/// Steps may be reported from any worker thread.
pub trait Progress: Sync {
    /// A stage named `what` begins, of `steps` steps.
    fn start(&self, what: &str, steps: u64);
    /// One more step of the stage under way is done.
    fn advance(&self);
    /// The stage under way has ended.
    fn finish(&self);
}

/// Progress shown nowhere.
#[derive(Clone, Copy, Debug, Default)]
pub struct NoProgress;

impl Progress for NoProgress {
    fn start(&self, _what: &str, _steps: u64) {}
    fn advance(&self) {}
    fn finish(&self) {}
}
