//! Systematic resampling on integer weights, the model of `resample_rtl` (`Resample`).

/// Systematic resampling on integer weights: pointer `j` is `(u0 + j 2^16) W`, compared
/// with `n 2^16 CDF_i`; `i` advances while the pointer is strictly beyond.
pub fn resample(weights: &[u16], w_sum: u32, u0: u32) -> Vec<usize> {
    let n = weights.len() as u64;
    let mut picks = Vec::with_capacity(weights.len());
    let mut left = u0 as u64 * w_sum as u64;
    let mut i = 0usize;
    let mut right = (n * weights[0] as u64) << 16;
    for _ in 0..weights.len() {
        while left > right && i + 1 < weights.len() {
            i += 1;
            right += (n * weights[i] as u64) << 16;
        }
        picks.push(i);
        left += (w_sum as u64) << 16;
    }
    picks
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resample_follows_the_weights() {
        let picks = resample(&[0, 65535, 0, 0], 65535, 1234);
        assert_eq!(picks, vec![1, 1, 1, 1]);
        // Pointers exactly on a CDF step stay (strictly beyond moves on, as in software).
        assert_eq!(resample(&[100, 100, 100, 100], 400, 0), vec![0, 0, 1, 2]);
        assert_eq!(resample(&[100, 100, 100, 100], 400, 1), vec![0, 1, 2, 3]);
        let picks = resample(&[300, 100, 0, 0], 400, 40000);
        assert_eq!(picks, vec![0, 0, 0, 1]);
    }
}
