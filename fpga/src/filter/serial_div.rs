//! The signed quotient of a weighted sum by the weights' sum, the model of `serial_div_rtl`
//! (`SerialDiv`, the magnitude's division).

/// `|S| / W` with the sign of `S` (truncation toward zero).
pub fn div_signed(s: i64, w: u32) -> i64 {
    let q = (s.unsigned_abs() / w as u64) as i64;
    if s < 0 {
        -q
    } else {
        q
    }
}
