//! The filter's PRNG, xorshift32 (13, 17, 5), the model of `xorshift_rtl` (`Xorshift32`).

/// The PRNG: xorshift32 (13, 17, 5). A seed of 0 is taken as 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Xorshift32(pub u32);

impl Xorshift32 {
    /// Seeded.
    pub fn new(seed: u32) -> Self {
        Xorshift32(if seed == 0 { 1 } else { seed })
    }
    /// The next state (also the output). Not an `Iterator`: the stream never ends and every
    /// draw's width is chosen by the caller ([`Self::signed16`], [`Self::unsigned16`]).
    #[allow(clippy::should_implement_trait)]
    pub fn next(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }
    /// A signed 16-bit draw (the top half of the next state): `u` in `[-1, 1)` as Q1.15.
    pub fn signed16(&mut self) -> i32 {
        (self.next() >> 16) as u16 as i16 as i32
    }
    /// An unsigned 16-bit draw: `u` in `[0, 1)` as Q0.16.
    pub fn unsigned16(&mut self) -> u32 {
        self.next() >> 16
    }
}
