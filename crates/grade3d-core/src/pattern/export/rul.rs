//! Grade rule tables as CSV and as an AAMA / ASTM D6673-10 `.RUL` file.
//!
//! # Contract
//!
//! Input: a [`GradeRuleTable`] — per piece, per grade point, the move
//! `(dx, dy)` of that point from the base size in every size, in the table's
//! size order, millimetres, piece axes (x right, y up, as the DXF).
//!
//! - [`rules_table_csv`]: RFC 4180 CSV (comma separated, `\n` line ends,
//!   fields with `,` `"` or line breaks quoted, quotes doubled). Header
//!   `piece,rule,node,label,<size>_dx,<size>_dy,…`, then one row per rule in
//!   table order. Numbers are written in full (shortest exact form).
//! - [`rules_rul`]: the `.RUL` text file of the AAMA/ASTM pattern
//!   interchange, the companion of the DXF ([`super::dxf`]) whose `# n` texts
//!   name these rules. Header lines `ASTM/D6673/RUL` (the first line of
//!   the files pattern CAD systems write), `AUTHOR:`, `PRODUCT:`,
//!   `VERSION:`, `CREATION DATE:` (`YYYY-MM-DD`) and `CREATION TIME:`
//!   (`HH:MM:SS`, UTC) where [`RulOptions::created`] gives them ([`Created`]),
//!   `UNITS: METRIC` (values in mm),
//!   `GRADE RULE TABLE:`,
//!   `NUMBER OF SIZES:`, `SIZE LIST:` (space separated), `SAMPLE SIZE:`; then
//!   per rule a line `RULE: DELTA n` followed by one line of `dx,dy` pairs,
//!   one pair per size in size order, separated by spaces; finally `END`. As
//!   the size list is space separated, whitespace inside a size name is
//!   written as `_` (in `SIZE LIST` and `SAMPLE SIZE`). No creation date or
//!   time unless given: this module reads no clock. The shell stamps them
//!   (the service with the request's `created` or the time it computes the
//!   result, `grade3d grade` with `--created`, `SOURCE_DATE_EPOCH` or the
//!   time it runs), so the same input and stamp give the same bytes.
//!
//! [`Created::from_rfc3339`] reads a stamp from an RFC 3339 date-time
//! (any offset, converted to UTC; fractions of a second dropped), and
//! [`Created::from_unix`] from seconds since 1970-01-01 UTC.
//!
//! # Failure modes
//!
//! None. A rule with fewer deltas than the table has sizes gets empty CSV
//! cells and zero moves in the `.RUL` (the base size's own move); deltas
//! beyond the number of sizes are left out. Non-finite numbers are written
//! as they print (`NaN`, `inf`).

use std::fmt::Write as _;

use glam::DVec2;

use super::ExportError;
use crate::pattern::piece::GradeRuleTable;

/// How the `.RUL` file is written.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct RulOptions {
    /// Decimals of the moves (count). Default 3 (µm).
    pub decimals: usize,
    /// `AUTHOR:` line. Default `grade3d`.
    pub author: String,
    /// `PRODUCT:` line. Default `grade3d`.
    pub product: String,
    /// `VERSION:` line. Default: this crate's version.
    pub version: String,
    /// `CREATION DATE:` and `CREATION TIME:` lines. Default `None`: left out.
    pub created: Option<Created>,
}

/// When a rule table was written, UTC: the `.RUL` header's `CREATION DATE:`
/// and `CREATION TIME:`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Created(chrono::DateTime<chrono::Utc>);

/// A creation stamp that cannot be read.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum CreatedError {
    /// Not an RFC 3339 date-time.
    #[error("`{text}` is not an RFC 3339 date-time (e.g. 2026-12-03T14:05:00Z): {reason}")]
    NotRfc3339 {
        /// What was given.
        text: String,
        /// Why it was refused.
        reason: String,
    },
    /// Seconds since the epoch outside what a date can hold.
    #[error("{0} s since 1970-01-01 is not a date")]
    OutOfRange(i64),
}

impl Created {
    /// 1970-01-01T00:00:00Z.
    pub const EPOCH: Self = Self(chrono::DateTime::UNIX_EPOCH);

    /// From an RFC 3339 date-time (`2026-12-03T15:05:00+01:00`), converted to
    /// UTC, whole seconds.
    ///
    /// # Errors
    /// [`CreatedError::NotRfc3339`].
    pub fn from_rfc3339(text: &str) -> Result<Self, CreatedError> {
        let t = chrono::DateTime::parse_from_rfc3339(text.trim())
            .map_err(|e| CreatedError::NotRfc3339 { text: text.to_owned(), reason: e.to_string() })?;
        Self::from_unix(t.timestamp())
    }

    /// From seconds since 1970-01-01T00:00:00Z (`SOURCE_DATE_EPOCH`).
    ///
    /// # Errors
    /// [`CreatedError::OutOfRange`].
    pub fn from_unix(seconds: i64) -> Result<Self, CreatedError> {
        chrono::DateTime::from_timestamp(seconds, 0).map(Self).ok_or(CreatedError::OutOfRange(seconds))
    }

    /// From a clock reading the caller took (this module reads no clock),
    /// whole seconds; a time before 1970 is [`Self::EPOCH`].
    pub fn from_system_time(t: std::time::SystemTime) -> Self {
        t.duration_since(std::time::UNIX_EPOCH)
            .ok()
            .and_then(|d| i64::try_from(d.as_secs()).ok())
            .and_then(|secs| Self::from_unix(secs).ok())
            .unwrap_or(Self::EPOCH)
    }

    /// `YYYY-MM-DD`.
    pub fn date(&self) -> String {
        self.0.format("%Y-%m-%d").to_string()
    }

    /// `HH:MM:SS`.
    pub fn time(&self) -> String {
        self.0.format("%H:%M:%S").to_string()
    }

    /// RFC 3339, `Z` for UTC (`2026-12-03T14:05:00Z`).
    pub fn to_rfc3339(&self) -> String {
        self.0.to_rfc3339_opts(chrono::SecondsFormat::Secs, true)
    }
}

impl Default for RulOptions {
    fn default() -> Self {
        Self {
            decimals: 3,
            author: "grade3d".to_string(),
            product: "grade3d".to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            created: None,
        }
    }
}

/// The rule table as CSV (module docs).
pub fn rules_table_csv(t: &GradeRuleTable) -> Result<String, ExportError> {
    let csv_error = |e: csv::Error| ExportError::Csv(e.to_string());
    // RFC 4180 through the `csv` crate (issue #16): fields quoted where needed, `\n` line ends
    let mut w = csv::WriterBuilder::new().terminator(csv::Terminator::Any(b'\n')).from_writer(Vec::new());
    let mut header = vec!["piece".to_string(), "rule".to_string(), "node".to_string(), "label".to_string()];
    for s in &t.sizes {
        header.push(format!("{s}_dx"));
        header.push(format!("{s}_dy"));
    }
    w.write_record(&header).map_err(csv_error)?;
    for piece in &t.pieces {
        for rule in &piece.rules {
            let mut row = vec![piece.piece.clone(), rule.number.to_string(), rule.node.to_string(), rule.label.clone()];
            for i in 0..t.sizes.len() {
                match rule.deltas.get(i) {
                    Some(d) => {
                        row.push(exact(d.x));
                        row.push(exact(d.y));
                    }
                    None => row.extend([String::new(), String::new()]),
                }
            }
            w.write_record(&row).map_err(csv_error)?;
        }
    }
    let bytes = w.into_inner().map_err(|e| ExportError::Csv(e.to_string()))?;
    String::from_utf8(bytes).map_err(|e| ExportError::Csv(e.to_string()))
}

/// The rule table as an AAMA/ASTM `.RUL` file with the default options (module docs).
pub fn rules_rul(t: &GradeRuleTable) -> String {
    rules_rul_with(t, &RulOptions::default())
}

/// The rule table as an AAMA/ASTM `.RUL` file (module docs).
pub fn rules_rul_with(t: &GradeRuleTable, opts: &RulOptions) -> String {
    let mut out = String::new();
    let sizes: Vec<String> = t.sizes.iter().map(|s| size_token(s)).collect();
    out.push_str("ASTM/D6673/RUL\n");
    let _ = writeln!(out, "AUTHOR: {}", one_line(&opts.author));
    let _ = writeln!(out, "PRODUCT: {}", one_line(&opts.product));
    let _ = writeln!(out, "VERSION: {}", one_line(&opts.version));
    if let Some(c) = &opts.created {
        let _ = writeln!(out, "CREATION DATE: {}", c.date());
        let _ = writeln!(out, "CREATION TIME: {}", c.time());
    }
    out.push_str("UNITS: METRIC\n");
    let _ = writeln!(out, "GRADE RULE TABLE: {}", one_line(&t.style));
    let _ = writeln!(out, "NUMBER OF SIZES: {}", sizes.len());
    let _ = writeln!(out, "SIZE LIST: {}", sizes.join(" "));
    let _ = writeln!(out, "SAMPLE SIZE: {}", size_token(&t.base_size));
    for rule in t.pieces.iter().flat_map(|p| &p.rules) {
        let _ = writeln!(out, "RULE: DELTA {}", rule.number);
        let pairs: Vec<String> = (0..sizes.len())
            .map(|i| {
                let d = rule.deltas.get(i).copied().unwrap_or(DVec2::ZERO);
                format!("{},{}", fixed(d.x, opts.decimals), fixed(d.y, opts.decimals))
            })
            .collect();
        let _ = writeln!(out, "{}", pairs.join(" "));
    }
    out.push_str("END\n");
    out
}

/// `v` with exactly `decimals` decimals (no negative zero: `-0.0001` is `0.000`).
fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    match s.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => s,
    }
}

/// `v` in its shortest exact form, `0` for negative zero.
fn exact(v: f64) -> String {
    if v == 0.0 {
        "0".to_string()
    } else {
        v.to_string()
    }
}

/// A size name as one token of the space-separated size list.
fn size_token(s: &str) -> String {
    let t: String = s.split_whitespace().collect::<Vec<_>>().join("_");
    if t.is_empty() {
        "_".to_string()
    } else {
        t
    }
}

/// Text on one line: line breaks become spaces.
fn one_line(s: &str) -> String {
    s.replace(['\r', '\n'], " ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::export::samples;

    #[test]
    fn creation_stamps_read_rfc3339_and_epoch_seconds_and_name_bad_ones() {
        let c = Created::from_rfc3339("2026-12-03T00:30:59.75-02:00").unwrap();
        assert_eq!((c.date(), c.time()), ("2026-12-03".to_string(), "02:30:59".to_string()));
        assert_eq!(c.to_rfc3339(), "2026-12-03T02:30:59Z");
        assert_eq!(Created::from_unix(1_796_265_059).unwrap(), c);
        assert_eq!(Created::from_unix(0).unwrap().to_rfc3339(), "1970-01-01T00:00:00Z");
        for bad in ["2026-12-03", "yesterday", "2026-13-01T00:00:00Z", ""] {
            let e = Created::from_rfc3339(bad).unwrap_err();
            assert!(matches!(&e, CreatedError::NotRfc3339 { text, .. } if text == bad), "{bad}: {e}");
        }
        assert_eq!(Created::from_unix(i64::MAX), Err(CreatedError::OutOfRange(i64::MAX)));
        let at = std::time::UNIX_EPOCH + std::time::Duration::from_millis(1_796_265_059_750);
        assert_eq!(Created::from_system_time(at), c);
        assert_eq!(
            Created::from_system_time(std::time::UNIX_EPOCH - std::time::Duration::from_secs(1)),
            Created::EPOCH
        );
    }

    #[test]
    fn rul_lists_sizes_and_one_delta_per_size() {
        let t = samples::rules();
        let rul = rules_rul(&t);
        let lines: Vec<&str> = rul.lines().collect();
        assert_eq!(lines[0], "ASTM/D6673/RUL");
        assert!(!rul.contains("CREATION"), "no date unless given");
        let dated = rules_rul_with(
            &t,
            &RulOptions {
                created: Some(Created::from_rfc3339("2026-12-02T17:40:00+01:00").unwrap()),
                ..RulOptions::default()
            },
        );
        assert!(dated.lines().any(|l| l == "CREATION DATE: 2026-12-02"));
        assert!(dated.lines().any(|l| l == "CREATION TIME: 16:40:00"));
        assert!(lines.contains(&"UNITS: METRIC"));
        assert!(lines.contains(&"GRADE RULE TABLE: Dress, \"summer\""));
        assert!(lines.contains(&"NUMBER OF SIZES: 3"));
        assert!(lines.contains(&"SIZE LIST: S M L_&_XL"));
        assert!(lines.contains(&"SAMPLE SIZE: M"));
        assert_eq!(lines.last(), Some(&"END"));
        let n_rules: usize = t.pieces.iter().map(|p| p.rules.len()).sum();
        let starts: Vec<usize> = (0..lines.len()).filter(|&i| lines[i].starts_with("RULE: DELTA ")).collect();
        assert_eq!(starts.len(), n_rules);
        // rule 1: the front's first corner (−x, −y) moves by the growth per size
        assert_eq!(lines[starts[0]], "RULE: DELTA 1");
        assert_eq!(lines[starts[0] + 1], "8.000,8.000 0.000,0.000 -8.000,-8.000");
        for &i in &starts {
            assert_eq!(lines[i + 1].split(' ').count(), 3, "{}", lines[i + 1]);
        }
        assert_eq!(rul, rules_rul(&t), "deterministic");
    }

    #[test]
    fn csv_has_a_row_per_rule_and_quotes_what_needs_it() {
        let mut t = samples::rules();
        t.pieces[0].rules[0].label = "waist, \"front\"".to_string();
        let csv = rules_table_csv(&t).unwrap();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], "piece,rule,node,label,S_dx,S_dy,M_dx,M_dy,L & XL_dx,L & XL_dy");
        let n_rules: usize = t.pieces.iter().map(|p| p.rules.len()).sum();
        assert_eq!(lines.len(), 1 + n_rules);
        assert_eq!(lines[1], "front & <side>,1,100,\"waist, \"\"front\"\"\",8,8,0,0,-8,-8");
        assert!(lines.iter().any(|l| l.starts_with("\"back \"\"left\"\" 'L' > x\",")));
        // a short rule gets empty cells
        t.pieces[0].rules[0].deltas.truncate(1);
        let short = rules_table_csv(&t).unwrap();
        assert!(short.lines().nth(1).is_some_and(|l| l.ends_with(",8,8,,,,")), "{short}");
    }
}
