//! SplitMix64: the small deterministic generator behind the seeded stimulus of the
//! fuzzers and the property tests (it is not part of the hardware; the filter's own PRNG is
//! [`pf::Xorshift32`](crate::filter::pf::Xorshift32)).

/// SplitMix64 with its state (the same state draws the same numbers).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SplitMix64(pub u64);

impl SplitMix64 {
    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// A `bits`-bit two's complement number (`0 < bits < 64`), from the top bits of the next
    /// draw.
    pub fn signed(&mut self, bits: u32) -> i64 {
        (self.next_u64() >> (64 - bits)) as i64 - (1 << (bits - 1))
    }

    /// A number below `n` (`n` > 0).
    pub fn below(&mut self, n: u64) -> u64 {
        self.next_u64() % n
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_the_published_sequence() {
        // The first outputs of SplitMix64 seeded with 1234567 (the reference implementation).
        let mut r = SplitMix64(1234567);
        assert_eq!(r.next_u64(), 6457827717110365317);
        assert_eq!(r.next_u64(), 3203168211198807973);
    }
}
