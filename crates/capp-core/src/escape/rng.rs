//! The escape's random numbers: xorshift32, seeded from the settings' seed
//! and the bits of the start configuration, so the board and the host draw
//! the same walks and searches to the bit.

/// A xorshift32 generator (never zero).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Rng {
    state: u32,
}

impl Rng {
    /// Seeded by FNV-1a over the bits of `start`, then `seed` (never zero).
    pub fn seeded(seed: u32, start: &[f32]) -> Self {
        let mut h: u32 = 0x811C_9DC5 ^ seed;
        for x in start {
            for b in x.to_bits().to_le_bytes() {
                h = (h ^ b as u32).wrapping_mul(0x0100_0193);
            }
        }
        Rng {
            state: if h == 0 { 0x9E37_79B9 } else { h },
        }
    }

    /// Uniform in `[-1, 1)`.
    pub fn uniform(&mut self) -> f32 {
        let mut x = self.state;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.state = x;
        (x >> 8) as f32 * (2.0 / (1u32 << 24) as f32) - 1.0
    }
}
