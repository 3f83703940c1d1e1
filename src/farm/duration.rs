//! Durations as people write them: "90s", "10m", "1h30m", "2.5h", "500ms".

use anyhow::{bail, ensure, Result};
use std::time::Duration;

/// Parses one or more `<number><unit>` terms (units ms, s, m, h, d; fractions allowed) and adds them.
pub fn parse_duration(text: &str) -> Result<Duration> {
    let mut rest = text.trim();
    ensure!(!rest.is_empty(), "empty duration: expected e.g. 90s, 10m, 1h30m or 2.5h");
    let mut seconds = 0.0;
    while !rest.is_empty() {
        let number_len = rest.find(|c: char| !(c.is_ascii_digit() || c == '.')).unwrap_or(rest.len());
        let unit_len = rest[number_len..].find(|c: char| !c.is_ascii_alphabetic()).unwrap_or(rest.len() - number_len);
        let (number, unit) = (&rest[..number_len], &rest[number_len..number_len + unit_len]);
        let Ok(value) = number.parse::<f64>() else {
            bail!("'{text}' is not a duration: expected e.g. 90s, 10m, 1h30m or 2.5h")
        };
        let scale = match unit {
            "ms" => 1e-3,
            "s" => 1.0,
            "m" | "min" => 60.0,
            "h" => 3600.0,
            "d" => 86400.0,
            "" => bail!("'{text}': give a unit (ms, s, m, h, d) after {number}"),
            other => bail!("'{text}': unknown unit '{other}' (ms, s, m, h, d)"),
        };
        seconds += value * scale;
        rest = &rest[number_len + unit_len..];
    }
    Duration::try_from_secs_f64(seconds).map_err(|_| anyhow::anyhow!("'{text}' is too long a duration"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn humane_forms() {
        let secs = |t: &str| parse_duration(t).unwrap().as_secs_f64();
        assert_eq!(secs("90s"), 90.0);
        assert_eq!(secs("10m"), 600.0);
        assert_eq!(secs("1h30m"), 5400.0);
        assert_eq!(secs("2.5h"), 9000.0);
        assert_eq!(secs("250ms"), 0.25);
        assert_eq!(secs("1d"), 86400.0);
    }

    #[test]
    fn rejects_garbage() {
        for bad in ["", "10", "m", "1.2.3s", "5 parsecs", "-3s", "1h 30m", "99999999999999999999999h"] {
            assert!(parse_duration(bad).is_err(), "{bad}");
        }
    }
}
