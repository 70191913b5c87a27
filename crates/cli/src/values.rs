//! Value parsers of the numeric options (clap `value_parser`s), and small helpers for what the
//! commands print (counts with their noun, paths).
//!
//! Every numeric option is range-checked when it is parsed, so a bad value is a usage error
//! naming the option and its range (`invalid value '-5' for '--samples <N>': must be an
//! integer in 1 ..= 1000000000`), never a value silently clamped or a run with NaN. Options
//! that take a number also accept a leading `-` (`allow_negative_numbers` / `allow_hyphen_values`
//! at the option), so `-n -5` is judged by the range, not taken for an unknown flag.

use std::fmt::Display;
use std::path::{Component, Path, PathBuf};

/// The unsigned integer types of the options.
pub(crate) trait Int: Copy + Display + Send + Sync + 'static {
    /// The largest value.
    const MAX: Self;
    /// As an `i128` (exact).
    fn wide(self) -> i128;
    /// From an `i128` in range.
    fn narrow(v: i128) -> Option<Self>;
}

macro_rules! int_impl {
    ($($t:ty),*) => {$(
        impl Int for $t {
            const MAX: Self = <$t>::MAX;
            fn wide(self) -> i128 {
                self as i128
            }
            fn narrow(v: i128) -> Option<Self> {
                <$t>::try_from(v).ok()
            }
        }
    )*};
}
int_impl!(u32, u64, usize);

fn int_with<T: Int>(
    min: T,
    max: T,
    message: String,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync {
    move |s: &str| {
        let v: i128 = s.trim().parse().map_err(|_| message.clone())?;
        if v < min.wide() || v > max.wide() {
            return Err(message.clone());
        }
        T::narrow(v).ok_or_else(|| message.clone())
    }
}

/// A parser of integers in `min ..= max`; the message names the range (`must be an integer
/// in 1 ..= 16`), also for a negative or non-integer value.
pub(crate) fn int<T: Int>(
    min: T,
    max: T,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync {
    int_with(min, max, format!("must be an integer in {min} ..= {max}"))
}

/// A parser of integers `≥ min` (`must be an integer ≥ 1`).
pub(crate) fn at_least<T: Int>(min: T) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync {
    int_with(min, T::MAX, format!("must be an integer ≥ {min}"))
}

/// A parser of seeds: any integer in `0 ..= 2^64 − 1`.
pub(crate) fn seed(s: &str) -> Result<u64, String> {
    s.trim()
        .parse()
        .map_err(|_| format!("must be an integer in 0 ..= {}", u64::MAX))
}

pub(crate) use samplers::End;

/// A parser of finite reals in an interval; NaN and ±∞ are refused with the same message,
/// e.g. `must be a finite number in [0, 90)` (the registry's, so sampler options and the
/// other options say ranges alike).
pub(crate) fn real(lo: End, hi: End) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    move |s: &str| samplers::options::parse_real(s, lo, hi)
}

/// Outgoing polar angles θo: degrees in `[0, 90)`.
pub(crate) fn theta_o(s: &str) -> Result<f64, String> {
    real(End::Closed(0.0), End::Open(90.0))(s)
}

/// Azimuths (φo, rotations): degrees in `[−360, 360]` (a direction needs no more turns, and a
/// huge angle would lose its precision in the reduction modulo 360°).
pub(crate) fn azimuth(s: &str) -> Result<f64, String> {
    real(End::Closed(-360.0), End::Closed(360.0))(s)
}

/// `n` and its noun, singular or plural: `1 test`, `2 tests`, `0 tests`.
pub(crate) fn count(n: usize, singular: &str, plural: &str) -> String {
    format!("{n} {}", if n == 1 { singular } else { plural })
}

/// `n` and its noun with an `s` for the plural: `1 thread`, `2 threads`.
pub(crate) fn counted(n: usize, noun: &str) -> String {
    count(n, noun, &format!("{noun}s"))
}

/// A path as it is printed in reports and messages: canonical (symbolic links and `..`
/// resolved; for a file that does not exist yet, its directory canonical), and relative to the
/// working directory when it lies below it. A path that cannot be resolved is printed with
/// its `.` components dropped.
pub(crate) fn display_path(path: &Path) -> String {
    let resolved = std::fs::canonicalize(path).ok().or_else(|| {
        let name = path.file_name()?;
        let parent = match path.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            _ => Path::new("."),
        };
        std::fs::canonicalize(parent).ok().map(|p| p.join(name))
    });
    let Some(resolved) = resolved else {
        return path
            .components()
            .filter(|c| !matches!(c, Component::CurDir))
            .collect::<PathBuf>()
            .display()
            .to_string();
    };
    let cwd = std::env::current_dir().and_then(std::fs::canonicalize).ok();
    match cwd.as_deref().and_then(|c| resolved.strip_prefix(c).ok()) {
        Some(rel) if !rel.as_os_str().is_empty() => rel.display().to_string(),
        _ => resolved.display().to_string(),
    }
}

/// The shard `K/N` of `--shard` (`study` and `validate`), if given; a malformed one is an input
/// error.
pub(crate) fn shard(arg: Option<&str>) -> crate::error::CliResult<Option<validation::Shard>> {
    arg.map(validation::Shard::parse)
        .transpose()
        .map_err(crate::error::CliError::input)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_are_range_checked_with_the_range_in_the_message() {
        let n = int::<u64>(1, 1_000);
        assert_eq!(n("5"), Ok(5));
        assert_eq!(n("-5").unwrap_err(), "must be an integer in 1 ..= 1000");
        assert!(n("0").is_err() && n("1001").is_err() && n("2.5").is_err());
        let spp = at_least::<usize>(1);
        assert_eq!(spp("0").unwrap_err(), "must be an integer ≥ 1");
        assert_eq!(
            seed("-1").unwrap_err(),
            format!("must be an integer in 0 ..= {}", u64::MAX)
        );
    }

    #[test]
    fn reals_must_be_finite_and_in_range() {
        assert_eq!(theta_o("45"), Ok(45.0));
        for bad in ["90", "-1", "NaN", "inf", "x"] {
            assert_eq!(
                theta_o(bad).unwrap_err(),
                "must be a finite number in [0, 90)"
            );
        }
        assert_eq!(azimuth("-360"), Ok(-360.0));
        assert!(azimuth("1e308").is_err() && azimuth("-inf").is_err());
        let n_max = real(End::Closed(1.0), End::None);
        assert_eq!(n_max("NaN").unwrap_err(), "must be a finite number ≥ 1");
        let eps = real(End::Open(0.0), End::Open(1.0));
        assert_eq!(eps("0").unwrap_err(), "must be a finite number in (0, 1)");
    }

    #[test]
    fn counts_agree_with_their_noun() {
        assert_eq!(counted(1, "thread"), "1 thread");
        assert_eq!(counted(2, "thread"), "2 threads");
        assert_eq!(counted(0, "test"), "0 tests");
        assert_eq!(count(1, "case", "cases"), "1 case");
    }

    #[test]
    fn paths_are_printed_resolved() {
        let dir = tempfile::tempdir().unwrap();
        let sub = dir.path().join("a");
        std::fs::create_dir(&sub).unwrap();
        let file = sub.join("f.txt");
        std::fs::write(&file, "x").unwrap();
        let canonical = std::fs::canonicalize(&file).unwrap();
        let dotted = sub.join("..").join("a").join(".").join("f.txt");
        assert_eq!(display_path(&dotted), canonical.display().to_string());
        // A file that does not exist yet: its directory is resolved.
        let new = sub.join("..").join("a").join("new.csv");
        assert_eq!(
            display_path(&new),
            canonical.with_file_name("new.csv").display().to_string()
        );
        assert!(!display_path(Path::new("/no/such/./dir/x")).contains("/./"));
    }
}
