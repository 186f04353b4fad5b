//! How long stages tell the caller about their progress.

/// Hears about progress; the CLI shows it as progress bars, libraries can ignore it.
pub trait Observer: Sync {
    /// A stage starts; `work` units of [`Observer::advance`] will follow (0 if unknown).
    fn stage(&self, name: &str, work: u64);
    fn advance(&self);
    fn finish(&self);
}

/// An observer that ignores everything.
pub struct Quiet;

impl Observer for Quiet {
    fn stage(&self, _: &str, _: u64) {}
    fn advance(&self) {}
    fn finish(&self) {}
}
