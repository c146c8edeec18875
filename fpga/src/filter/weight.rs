//! The temperature and a particle's weight from its cost excess, the model of `weight_rtl`
//! (`Weight`).

use crate::common::format::EXP_ENTRIES;

/// The smallest temperature exponent (`2 Q_k >= 2^5` cost LSBs; `q_mul` stays `2^16`).
pub const MIN_TEMPER_EXP: u32 = 5;

/// The temperature exponent: `e = max(e_Q, bitlen(m) - 2, 5)` with `m` the excess of rank
/// `n / 2` (0-based) among the sorted excesses `c_i - c_min`: `2 Q_k = 2^e` lies between a
/// quarter and a half of the median excess, or is the ICP variance's `2 Q` if larger.
pub fn temper(excess: &[u64], temper_exp: u8) -> u32 {
    let k = excess.len() / 2;
    let b = (0..=48u32).find(|&p| excess.iter().filter(|&&e| p == 48 || e < (1u64 << p)).count() > k).unwrap_or(48);
    (temper_exp as u32 & 63).max(b.saturating_sub(2)).max(MIN_TEMPER_EXP)
}

/// A weight: `EXP[min(255, excess >> (e - 5))]`.
pub fn weight(excess: u64, e: u32, table: &[u16; EXP_ENTRIES]) -> u16 {
    let j = (excess >> (e - MIN_TEMPER_EXP)).min(EXP_ENTRIES as u64 - 1);
    table[j as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temper_picks_the_median_bit_length() {
        // Excesses 0, 10, 100, 1000: rank 2 is 100, bitlen 7, so e = max(e_Q, 5, 5).
        assert_eq!(temper(&[0, 10, 100, 1000], 0), 5);
        assert_eq!(temper(&[0, 1 << 20, 1 << 30, 1 << 40], 0), 29);
        assert_eq!(temper(&[0, 1 << 20, 1 << 30, 1 << 40], 40), 40);
        assert_eq!(temper(&[0], 0), 5);
    }
}
