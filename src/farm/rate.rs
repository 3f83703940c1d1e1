//! Rates over measured time, which may be none: a resume that adds no samples renders for zero
//! seconds, and 0 / 0 would print as NaN.

/// `count` per second over `seconds`; `None` when nothing was counted or no time was measured.
pub fn per_second(count: f64, seconds: f64) -> Option<f64> {
    (count > 0.0 && seconds > 0.0).then(|| count / seconds)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nothing_measured_is_no_rate() {
        assert_eq!(per_second(10.0, 2.0), Some(5.0));
        assert_eq!(per_second(0.0, 0.0), None);
        assert_eq!(per_second(10.0, 0.0), None);
        assert_eq!(per_second(0.0, 2.0), None);
    }
}
