//! xorshift64*: deterministic random numbers for the fuzz tests, no dependency.

pub struct Rng(pub u64);

impl Rng {
    pub fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545F4914F6CDD1D)
    }

    pub fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }

    pub fn chance(&mut self, p: f64) -> bool {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }

    /// One of `cases` equally likely draws: a value of `specials` (the first cases), else an
    /// integer in [-10000, 10000].
    pub fn real(&mut self, specials: &[f64], cases: u64) -> f64 {
        match specials.get(self.below(cases) as usize) {
            Some(&x) => x,
            None => self.below(20001) as f64 - 10000.0,
        }
    }
}
