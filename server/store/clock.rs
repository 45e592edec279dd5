//! The time as every table stores it: RFC 3339 text in UTC with milliseconds
//! (`2026-05-20T10:44:36.123Z`), the form SQLite's `strftime('%Y-%m-%dT%H:%M:%fZ', 'now')` gave
//! before this module existed, so rows written before and after read alike.
//!
//! The store makes these texts itself and binds them, rather than asking the database for the
//! time: SQLite and PostgreSQL spell "now" and date arithmetic differently, and one text made in
//! one place is the same on both. Spans (the paper's T, a session's duration) are computed here
//! from the stored texts for the same reason. Fixed-width text in UTC sorts as time does, so
//! `ORDER BY` and `MAX` on these columns stay right on either database.

use std::time::{SystemTime, UNIX_EPOCH};

const MS_PER_DAY: i64 = 86_400_000;

/// The current time as stored text.
pub(super) fn now() -> String {
    let ms = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_millis() as i64);
    text(ms)
}

/// Milliseconds since the Unix epoch as stored text.
fn text(ms: i64) -> String {
    let (days, in_day) = (ms.div_euclid(MS_PER_DAY), ms.rem_euclid(MS_PER_DAY));
    let (y, m, d) = civil_from_days(days);
    let s = in_day / 1000;
    format!(
        "{y:04}-{m:02}-{d:02}T{:02}:{:02}:{:02}.{:03}Z",
        s / 3600,
        s / 60 % 60,
        s % 60,
        in_day % 1000
    )
}

/// Seconds since the Unix epoch of a stored time (`YYYY-MM-DDTHH:MM:SS[.fff]Z`); `None` for text
/// in another form.
pub(super) fn seconds(text: &str) -> Option<f64> {
    let b = text.as_bytes();
    let num = |range: std::ops::Range<usize>| -> Option<i64> {
        let part = text.get(range)?;
        part.bytes()
            .all(|c| c.is_ascii_digit())
            .then(|| part.parse().ok())?
    };
    if b.len() < 20 || b[4] != b'-' || b[7] != b'-' || b[10] != b'T' || b[13] != b':' {
        return None;
    }
    if b[16] != b':' || b[b.len() - 1] != b'Z' {
        return None;
    }
    let (y, mo, d) = (num(0..4)?, num(5..7)?, num(8..10)?);
    let (h, mi, s) = (num(11..13)?, num(14..16)?, num(17..19)?);
    if !(1..=12).contains(&mo) || !(1..=31).contains(&d) || h > 23 || mi > 59 || s > 60 {
        return None;
    }
    let fraction = match &text[19..text.len() - 1] {
        "" => 0.0,
        f if f.len() > 1 && f.starts_with('.') && f[1..].bytes().all(|c| c.is_ascii_digit()) => {
            f[1..].parse::<f64>().ok()? / 10f64.powi(f.len() as i32 - 1)
        }
        _ => return None,
    };
    let whole = days_from_civil(y, mo, d) * 86_400 + h * 3600 + mi * 60 + s;
    Some(whole as f64 + fraction)
}

/// Seconds from one stored time to another; `None` when either is missing or unreadable.
pub(super) fn span(from: Option<&str>, to: Option<&str>) -> Option<f64> {
    Some(seconds(to?)? - seconds(from?)?)
}

/// Days since 1970-01-01 of a proleptic Gregorian date (Howard Hinnant's `days_from_civil`).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let doy = (153 * ((m + 9) % 12) + 2) / 5 + d - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

/// The date `days` after 1970-01-01 (Hinnant's `civil_from_days`).
fn civil_from_days(days: i64) -> (i64, i64, i64) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    (yoe + era * 400 + i64::from(m <= 2), m, d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn known_times_read_and_write_as_sqlite_wrote_them() {
        assert_eq!(text(0), "1970-01-01T00:00:00.000Z");
        // A leap day, and the last millisecond of a leap year.
        assert_eq!(text(951_782_400_000), "2000-02-29T00:00:00.000Z");
        assert_eq!(text(978_307_199_999), "2000-12-31T23:59:59.999Z");
        assert_eq!(text(1_779_273_876_123), "2026-05-20T10:44:36.123Z");
        assert_eq!(seconds("2026-05-20T10:44:36.123Z"), Some(1_779_273_876.123));
        assert_eq!(seconds("2026-05-20T10:44:36Z"), Some(1_779_273_876.0));
        for bad in [
            "",
            "2026-05-20 10:44:36.123Z",
            "2026-05-20T10:44:36.123",
            "2026-13-01T00:00:00Z",
        ] {
            assert_eq!(seconds(bad), None, "{bad:?}");
        }
    }

    #[test]
    fn now_is_in_the_stored_form() {
        let t = now();
        assert_eq!(t.len(), 24, "{t}");
        assert!(seconds(&t).unwrap() > 1.7e9, "{t}");
    }

    proptest! {
        /// Every millisecond from 1900 to 2400 reads back as itself, and text order is time
        /// order (what `ORDER BY` and `MAX` rely on).
        #[test]
        fn texts_read_back_and_sort_as_time(a in -2_208_988_800_000i64..13_569_465_600_000, b in -2_208_988_800_000i64..13_569_465_600_000) {
            prop_assert!((seconds(&text(a)).unwrap() - a as f64 / 1000.0).abs() < 1e-6);
            prop_assert_eq!(text(a).cmp(&text(b)), a.cmp(&b));
        }
    }
}
