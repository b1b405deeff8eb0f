//! Time stamps of the CSV dialect, rule 5 of the [line rules](super): times of day and
//! date-times as seconds, and a column of times of day read across midnight.

/// A time stamp as seconds: `HH:MM:SS[.fff]` (seconds of the day),
/// `YYYY-MM-DD[T| ]HH:MM:SS[.fff][Z]` (seconds since 1970-01-01, UTC as written: no time zone
/// is applied) or `M:SS.fff` (a stopwatch's minutes and seconds since the start, minutes past
/// 59 too: `75:02.5`; the fraction is what tells it from a time of day without seconds,
/// `18:55`, which is refused). A decimal comma is accepted in the seconds. A time of day may
/// end in `AM` or `PM` (a 12-hour clock, hours 1–12). The date may also be written with
/// slashes, `M/D/YYYY` as US software writes it (`D/M/YYYY` when the first number cannot be a
/// month, `YYYY/M/D` with the year first), or with dots, `D.M.YYYY` (`YYYY.M.D`): a record's
/// stamps differ in their time of day, so the order of month and day matters only across a
/// midnight. `None` for anything else.
pub fn parse_clock(field: &str) -> Option<f64> {
    clock(field).map(|c| c.seconds)
}

/// A parsed stamp: its seconds ([`parse_clock`]) and whether it carried a date.
struct Clock {
    seconds: f64,
    dated: bool,
}

fn clock(field: &str) -> Option<Clock> {
    let (field, pm) = twelve_hour(field.trim());
    let field = field.strip_suffix('Z').unwrap_or(field);
    let (date, time) = match field.split_once(['T', ' ']) {
        Some((d, t)) => (Some(d), t.trim()),
        None => (None, field),
    };
    let parts: Vec<&str> = time.split(':').collect();
    let seconds = |p: &str| -> Option<f64> {
        let p = p.replacen(',', ".", 1);
        let s: f64 = p.parse().ok()?;
        (p.as_bytes().first()?.is_ascii_digit() && (0.0..61.0).contains(&s)).then_some(s)
    };
    let day_s = match parts[..] {
        [h, m, s] => {
            let (h, m, s) = (whole(h)?, whole(m)?, seconds(s)?);
            let h = match pm {
                None => h,
                Some(_) if !(1..=12).contains(&h) => return None,
                Some(pm) => h % 12 + if pm { 12 } else { 0 },
            };
            if h > 23 || m > 59 {
                return None;
            }
            f64::from(h * 3600 + m * 60) + s
        }
        // Minutes and seconds since a start: a fraction, no date.
        [m, s] if date.is_none() && pm.is_none() && s.contains(['.', ',']) => {
            f64::from(whole(m)?.checked_mul(60)?) + seconds(s)?
        }
        _ => return None,
    };
    let Some(date) = date else {
        return Some(Clock {
            seconds: day_s,
            dated: false,
        });
    };
    let (y, mo, d) = civil_date(date)?;
    Some(Clock {
        seconds: days_from_civil(y, mo, d) as f64 * DAY_S + day_s,
        dated: true,
    })
}

/// A field of digits only as a number (no sign, no space, not empty).
fn whole(p: &str) -> Option<u32> {
    (!p.is_empty() && p.bytes().all(|b| b.is_ascii_digit()))
        .then(|| p.parse().ok())
        .flatten()
}

/// The field without a trailing `AM` or `PM` (any case, a space before it or not), and whether
/// it was `PM` (`None` without either).
fn twelve_hour(field: &str) -> (&str, Option<bool>) {
    let n = field.len();
    if n < 2 || !field.is_char_boundary(n - 2) {
        return (field, None);
    }
    let (rest, tail) = field.split_at(n - 2);
    let pm = match tail.to_ascii_uppercase().as_str() {
        "AM" => false,
        "PM" => true,
        _ => return (field, None),
    };
    (rest.trim_end(), Some(pm))
}

/// Year, month and day of a date written `YYYY-MM-DD`, with slashes or with dots
/// ([`parse_clock`]'s doc).
fn civil_date(date: &str) -> Option<(i64, u32, u32)> {
    let sep = ['-', '/', '.'].into_iter().find(|&c| date.contains(c))?;
    let parts: Vec<&str> = date.split(sep).collect();
    let [a, b, c] = parts[..] else {
        return None;
    };
    let (a, b, c, year_first) = (whole(a)?, whole(b)?, whole(c)?, a.len() == 4);
    let (y, mo, d) = match sep {
        _ if year_first => (a, b, c),
        '-' => return None,
        // Month first, as US software writes it, unless the first cannot be a month.
        '/' if a > 12 => (c, b, a),
        '/' => (c, a, b),
        _ => (c, b, a),
    };
    if !(1..=12).contains(&mo) || !(1..=31).contains(&d) {
        return None;
    }
    Some((i64::from(y), mo, d))
}

/// One day, s.
const DAY_S: f64 = 86_400.0;

/// The stamps of one time column read in order ([`ClockColumn::read`]): a time of day without
/// a date that falls back by more than half a day from the one before it has passed midnight,
/// and a day is added from there on (23:59:59.9 then 00:00:00.1 is 0.2 s later); one that
/// jumps ahead by more than half a day is a row from before that midnight. Stamps with a date
/// are read as they are.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ClockColumn {
    last: Option<f64>,
    days: i64,
    /// Midnights passed so far.
    pub midnights: usize,
}

impl ClockColumn {
    /// The next stamp of the column as seconds ([`parse_clock`], days added after midnight).
    pub fn read(&mut self, field: &str) -> Option<f64> {
        let c = clock(field)?;
        if c.dated {
            return Some(c.seconds);
        }
        if let Some(last) = self.last {
            if c.seconds < last - DAY_S / 2.0 {
                self.days += 1;
                self.midnights = self.midnights.max(usize::try_from(self.days).unwrap_or(0));
            } else if c.seconds > last + DAY_S / 2.0 {
                self.days -= 1;
            }
        }
        self.last = Some(c.seconds);
        Some(c.seconds + self.days as f64 * DAY_S)
    }
}

/// Days since 1970-01-01 of a proleptic Gregorian date (H. Hinnant, "chrono-Compatible
/// Low-Level Date Algorithms", `days_from_civil`).
fn days_from_civil(y: i64, m: u32, d: u32) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400;
    let mp = i64::from((m + 9) % 12);
    let doy = (153 * mp + 2) / 5 + i64::from(d) - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    era * 146_097 + doe - 719_468
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clock_stamps_as_seconds() {
        assert_eq!(parse_clock("18:55:23.5"), Some(68_123.5));
        // A stopwatch's minutes and seconds, minutes past an hour too.
        assert_eq!(parse_clock("00:01.250"), Some(1.25));
        assert_eq!(parse_clock("75:02,5"), Some(4502.5));
        for not in [
            "1:2:3:4",
            "12:",
            ":30",
            "1:75",
            "-1:30",
            "2024-08-13 12:30",
            "1:+5",
        ] {
            assert_eq!(parse_clock(not), None, "{not}");
        }
        assert_eq!(parse_clock("1970-01-02 00:00:01"), Some(86_401.0));
        assert_eq!(parse_clock("2000-03-01T00:00:00Z"), Some(951_868_800.0));
        let a = parse_clock("2024-08-13 18:55:23,120").unwrap();
        let b = parse_clock("2024-08-13T18:55:24.130").unwrap();
        assert!((b - a - 1.01).abs() < 1e-6, "{}", b - a);
        for bad in ["18:55", "25:00:00", "2024-13-01 00:00:00", "12.5", "a:b:c"] {
            assert_eq!(parse_clock(bad), None, "{bad}");
        }
    }

    #[test]
    fn twelve_hour_clocks_and_dates_with_slashes_or_dots() {
        let iso = parse_clock("2024-08-13 18:55:23.140").unwrap();
        for same in [
            "08/13/2024 06:55:23.140 PM",
            "8/13/2024 6:55:23.140PM",
            "13/08/2024 18:55:23.140",
            "2024/08/13 18:55:23.140",
            "13.08.2024 18:55:23,140",
        ] {
            let t = parse_clock(same).unwrap_or_else(|| panic!("{same}"));
            assert!((t - iso).abs() < 1e-6, "{same}: {}", t - iso);
        }
        // Month first when both could be a month: 03/04 is March 4.
        let march = parse_clock("2024-03-04 00:00:00").unwrap();
        assert_eq!(parse_clock("03/04/2024 12:00:00 am"), Some(march));
        assert_eq!(parse_clock("12:00:00 PM"), Some(43_200.0));
        assert_eq!(parse_clock("12:30:00 AM"), Some(1_800.0));
        for bad in [
            "13:00:00 PM",
            "00:10:00 AM",
            "01:05.5 PM",
            "13/13/2024 00:00:00",
            "13-08-2024 00:00:00",
            "1/2 00:00:00",
            "PM",
        ] {
            assert_eq!(parse_clock(bad), None, "{bad}");
        }
    }

    #[test]
    fn times_of_day_keep_increasing_across_midnight() {
        let mut c = ClockColumn::default();
        let t: Vec<f64> = [
            "23:59:59.8",
            "23:59:59.9",
            "00:00:00.1",
            "00:00:00.0",
            "00:00:00.2",
        ]
        .iter()
        .map(|f| c.read(f).unwrap())
        .collect();
        assert!((t[2] - t[1] - 0.2).abs() < 1e-9, "{t:?}");
        // A row a little out of order stays a little out of order, on the same day.
        assert!((t[3] - t[1] - 0.1).abs() < 1e-9, "{t:?}");
        assert!((t[4] - t[1] - 0.3).abs() < 1e-9, "{t:?}");
        assert_eq!(c.midnights, 1);
        // A late row from before midnight, then the next day again: one midnight.
        assert!((c.read("23:59:59.95").unwrap() - t[1] - 0.05).abs() < 1e-9);
        assert!((c.read("00:00:00.3").unwrap() - t[1] - 0.4).abs() < 1e-9);
        assert_eq!(c.midnights, 1);
        // Two days on: two midnights.
        let mut c = ClockColumn::default();
        for f in ["22:00:00", "04:00:00", "14:00:00", "23:00:00", "02:00:00"] {
            c.read(f).unwrap();
        }
        assert_eq!(c.midnights, 2);
        // Stamps with a date are read as they are.
        let mut c = ClockColumn::default();
        let a = c.read("2024-08-13 23:59:59.9").unwrap();
        let b = c.read("2024-08-14 00:00:00.1").unwrap();
        assert!((b - a - 0.2).abs() < 1e-6);
        assert_eq!((c.midnights, c.read("x")), (0, None));
    }
}
