//! Deterministic pseudo-random numbers for tests: scattered inputs checked against a
//! brute-force reference, the same scatter on every run and machine (no `rand`).

/// A 64-bit linear congruential sequence (Knuth's MMIX constants), its high 53 bits as the
/// number.
pub(crate) struct SeededRandom(u64);

impl SeededRandom {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next number, in [0, 1).
    pub fn unit(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The next number, in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}
