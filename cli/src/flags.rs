//! Flags checked against the settings table (`vibcam_common::setting::table`): their help,
//! their command-line default and their range come from the setting's one row, so a flag
//! spelled the same way parses, validates and is described the same way in every command and
//! every binary.

use vibcam_common::setting::table::{self, DefaultValue};
use vibcam_common::setting::Naming;

/// The help of `key`'s row of the settings table (the first row that names it: the row of a
/// group of flags several commands share), as the command line spells it.
pub fn help(key: &str) -> String {
    table::row(key).help_for(Naming::Cli)
}

/// The help of `command`'s own row of `key`.
pub fn help_in(command: &str, key: &str) -> String {
    table::find(command, key)
        .unwrap_or_else(|| panic!("no setting `{key}` for `{command}`"))
        .help_for(Naming::Cli)
}

/// The default the command line fills in for `key` (its row's `Given`).
pub fn given(key: &str) -> &'static str {
    match table::row(key).default {
        DefaultValue::Given(d) => d,
        d => panic!("`{key}` has no default the command line fills in: {d:?}"),
    }
}

/// Why a value is refused by `row`: the range it needs, in the row's unit (clap names the flag).
fn refusal(row: &table::Setting) -> String {
    let unit = match row.unit {
        "" => String::new(),
        u => format!(" ({u})"),
    };
    format!("{} is needed{unit}", row.range())
}

/// `command`'s row of `key` (`None`: the first row naming it).
fn row_of(command: Option<&str>, key: &str) -> &'static table::Setting {
    match command {
        Some(c) => table::find(c, key).unwrap_or_else(|| panic!("no `{key}` for `{c}`")),
        None => table::row(key),
    }
}

/// A whole-number flag checked against `key`'s row.
pub fn whole<T: TryFrom<u64>>(
    key: &'static str,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static {
    whole_in(None, key)
}

/// A whole-number flag checked against `command`'s row of `key` (`None`: its first row).
pub fn whole_in<T: TryFrom<u64>>(
    command: Option<&'static str>,
    key: &'static str,
) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static {
    let row = row_of(command, key);
    move |s: &str| {
        s.trim()
            .parse::<u64>()
            .ok()
            .filter(|v| row.admits(*v as f64))
            .and_then(|v| T::try_from(v).ok())
            .ok_or_else(|| refusal(row))
    }
}

/// A number flag checked against `key`'s row; a positive one may be a ratio (`30000/1001`).
pub fn number(key: &'static str) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    number_in(None, key)
}

/// A number flag checked against `command`'s row of `key` (`None`: its first row).
pub fn number_in(
    command: Option<&'static str>,
    key: &'static str,
) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync {
    let row = row_of(command, key);
    move |s: &str| {
        let v = match s.contains('/') {
            true => parse_rate(s).ok(),
            false => s.trim().parse::<f64>().ok(),
        };
        v.filter(|v| row.admits(*v)).ok_or_else(|| refusal(row))
    }
}

/// Parses `--coverage P`: a probability strictly between 0 and 1 (study and merge).
pub fn parse_coverage(s: &str) -> Result<f64, String> {
    let p: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    if p > 0.0 && p < 1.0 {
        Ok(p)
    } else {
        Err(format!(
            "{p} must lie strictly between 0 and 1 (0.95 for 95 %)"
        ))
    }
}

/// An integer flag's range, checked by clap (the message names the flag and the range).
pub fn int_range(
    range: std::ops::RangeInclusive<u64>,
) -> clap::builder::RangedU64ValueParser<usize> {
    clap::builder::RangedU64ValueParser::<usize>::new().range(range)
}

/// A rate as users write it: a decimal (`120`, `29.97`) or a ratio (`30000/1001`, as video
/// containers state NTSC rates), finite and > 0.
pub fn parse_rate(s: &str) -> Result<f64, String> {
    let v = match s.split_once('/') {
        Some((n, d)) => {
            let (n, d): (f64, f64) = (
                n.trim()
                    .parse()
                    .map_err(|_| format!("`{s}`: expected N or N/D"))?,
                d.trim()
                    .parse()
                    .map_err(|_| format!("`{s}`: expected N or N/D"))?,
            );
            n / d
        }
        None => s
            .trim()
            .parse()
            .map_err(|_| format!("`{s}`: expected a number or a ratio N/D"))?,
    };
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(format!("`{s}`: must be a positive rate"))
    }
}

/// A flag whose values are a library type's choices, spelled by its `name` (declared once,
/// in the library): clap lists them in `--help` and refuses any other.
pub fn choice<T: Copy + Send + Sync + 'static>(
    all: &'static [T],
    name: fn(T) -> &'static str,
) -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(all.iter().map(|t| name(*t))).try_map(
        move |s: String| {
            all.iter()
                .copied()
                .find(|t| name(*t) == s)
                .ok_or_else(|| format!("no choice {s}"))
        },
    )
}
