//! Size charts: one row of body measurements per size, in CSV or JSON,
//! cm/mm/m/inches per chart or per value → validated targets in metres.
//!
//! Columns are measurement IDs of [`MeasurementId`] (ISO 8559-1 names),
//! plus the aliases ASTM D5585 uses: `upper_chest_girth` is the chest
//! girth; `waist_girth_curvy` and `waist_girth_straight` are the waist
//! girths of ASTM's two figure types — one body has one waist, so the
//! chart's [`FigureType`] picks which column is the waist girth and the
//! other is kept as an alternative, not a target.
//!
//! Every value is checked against a plausible adult range (in cm, see
//! [`plausible_range_cm`]). A value declared in cm that is implausible but
//! would be plausible in inches (a 36 cm bust) is rejected as
//! [`SizeChartError::LikelyInches`]; every error names the size and column.
//!
//! CSV: a header row with `size`, optional `unit`, and measurement columns;
//! lines starting with `#` are comments. JSON:
//! `{"unit": "in", "figure": "curvy", "sizes": [{"size": "8", "unit": "in",
//! "measurements": {"bust_girth": 36.25, "waist_girth": {"value": 71, "unit": "cm"}}}]}`.

use std::collections::BTreeMap;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::body::measure::MeasurementId;

/// A length unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Unit {
    /// Millimetres.
    Mm,
    /// Centimetres.
    Cm,
    /// Metres.
    M,
    /// Inches.
    In,
}

impl Unit {
    /// Metres per unit.
    pub fn metres(self) -> f64 {
        match self {
            Unit::Mm => 1e-3,
            Unit::Cm => 1e-2,
            Unit::M => 1.0,
            Unit::In => 0.0254,
        }
    }
}

impl FromStr for Unit {
    type Err = ();
    fn from_str(s: &str) -> Result<Self, ()> {
        match s.trim().to_ascii_lowercase().as_str() {
            "mm" => Ok(Unit::Mm),
            "cm" => Ok(Unit::Cm),
            "m" => Ok(Unit::M),
            "in" | "inch" | "inches" | "\"" => Ok(Unit::In),
            _ => Err(()),
        }
    }
}

/// ASTM D5585 figure type: which waist column is the waist girth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum FigureType {
    /// `waist_girth_curvy` (default).
    #[default]
    Curvy,
    /// `waist_girth_straight`.
    Straight,
}

/// Whose body a chart describes: the sex of its mannequins' model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum Sex {
    /// Women's (misses', petites', …) charts.
    #[default]
    Female,
    /// Men's charts.
    Male,
}

/// How a chart's [`Sex`] was settled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(rename_all = "lowercase")]
pub enum SexSource {
    /// The chart (or the request) says it.
    Stated,
    /// From its columns: a bust, underbust or ASTM figure-type waist makes a
    /// women's chart; a chest girth without them a men's.
    Inferred,
    /// Neither: women's, the default.
    Default,
}

/// One size: targets in metres.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SizeRow {
    /// Size label.
    pub size: String,
    /// Target measurements, metres.
    pub targets: BTreeMap<MeasurementId, f64>,
    /// Columns read but not used as targets (the other figure type's waist), metres.
    #[serde(default)]
    pub alternatives: BTreeMap<String, f64>,
}

/// A parsed size chart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SizeChart {
    /// The figure type used for the waist (women's charts; ASTM D5585).
    pub figure: FigureType,
    /// Whose body the chart describes.
    pub sex: Sex,
    /// How `sex` was settled.
    pub sex_source: SexSource,
    /// Rows in chart order.
    pub rows: Vec<SizeRow>,
}

impl SizeChart {
    /// The chart steps of measurement `m` between consecutive rows, m
    /// (`rows[k+1] − rows[k]`); `None` where a row lacks it.
    pub fn steps(&self, m: MeasurementId) -> Option<Vec<f64>> {
        let values: Option<Vec<f64>> = self.rows.iter().map(|r| r.targets.get(&m).copied()).collect();
        values.map(|v| v.windows(2).map(|w| w[1] - w[0]).collect())
    }
}

/// Limits on a size chart.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SizeChartOptions {
    /// Most sizes accepted in one chart. Default 40.
    pub max_sizes: usize,
    /// Figure type when the chart does not say. Default curvy.
    pub figure: FigureType,
    /// Sex when the chart does not say (else inferred from its columns).
    /// Default none.
    pub sex: Option<Sex>,
}

impl Default for SizeChartOptions {
    fn default() -> Self {
        Self { max_sizes: 40, figure: FigureType::Curvy, sex: None }
    }
}

/// What is wrong with a size chart.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SizeChartError {
    /// Not parseable as CSV or JSON.
    #[error("size chart syntax: {0}")]
    Syntax(String),
    /// A column (or JSON key) the vocabulary doesn't know.
    #[error("unknown measurement column `{column}`")]
    UnknownColumn {
        /// The column name.
        column: String,
    },
    /// No `size` column / field.
    #[error("the size chart has no `size` column")]
    NoSizeColumn,
    /// An unknown unit.
    #[error("size `{size}`: unknown unit `{unit}` (use mm, cm, m or in)")]
    UnknownUnit {
        /// The size.
        size: String,
        /// The unit string.
        unit: String,
    },
    /// A value that is not a finite number.
    #[error("size `{size}`, `{column}`: `{value}` is not a finite number")]
    NotANumber {
        /// The size.
        size: String,
        /// The column.
        column: String,
        /// The text found.
        value: String,
    },
    /// A value outside the plausible adult range.
    #[error("size `{size}`, `{column}`: {value_cm:.1} cm is outside the plausible range {min_cm}–{max_cm} cm")]
    OutOfRange {
        /// The size.
        size: String,
        /// The column.
        column: String,
        /// The value, cm.
        value_cm: f64,
        /// Lower bound, cm.
        min_cm: f64,
        /// Upper bound, cm.
        max_cm: f64,
    },
    /// A value declared in cm that is plausible only in inches.
    #[error("size `{size}`, `{column}`: {value} cm is implausible; it looks like inches ({value} in = {as_cm:.1} cm)")]
    LikelyInches {
        /// The size.
        size: String,
        /// The column.
        column: String,
        /// The value as given.
        value: f64,
        /// The value read as inches, in cm.
        as_cm: f64,
    },
    /// No sizes at all.
    #[error("the size chart has no sizes")]
    Empty,
    /// More sizes than allowed.
    #[error("the size chart has {count} sizes; at most {max} are accepted")]
    TooManySizes {
        /// Count given.
        count: usize,
        /// The limit.
        max: usize,
    },
    /// The same size twice.
    #[error("size `{size}` appears twice")]
    DuplicateSize {
        /// The size.
        size: String,
    },
    /// Rows of a CSV chart's `sex` column disagree.
    #[error("size `{size}`: sex `{sex}` differs from the chart's first row (one chart, one sex)")]
    ConflictingSex {
        /// The size.
        size: String,
        /// Its `sex` cell.
        sex: String,
    },
    /// A `sex` that is neither `female` nor `male`.
    #[error("sex `{sex}`: expected `female` or `male`")]
    UnknownSex {
        /// The value given.
        sex: String,
    },
    /// A row with no measurement.
    #[error("size `{size}` has no measurements")]
    EmptyRow {
        /// The size.
        size: String,
    },
}

/// Plausible adult range of a measurement, cm.
pub fn plausible_range_cm(id: MeasurementId) -> (f64, f64) {
    use MeasurementId as M;
    match id {
        M::Stature => (120.0, 220.0),
        M::NeckBaseGirth => (25.0, 65.0),
        M::ShoulderGirth => (70.0, 170.0),
        M::ChestGirth | M::BustGirth => (60.0, 180.0),
        M::UnderbustGirth => (50.0, 170.0),
        M::WaistGirth => (45.0, 190.0),
        M::HipGirth => (60.0, 200.0),
        M::ThighGirth => (35.0, 110.0),
        M::KneeGirth => (25.0, 70.0),
        M::AnkleGirth => (15.0, 45.0),
        M::ArmscyeGirth => (25.0, 75.0),
        M::WaistHeight => (70.0, 140.0),
        M::HipHeight => (55.0, 120.0),
        M::CrotchHeight => (50.0, 110.0),
        M::ShoulderWidth => (25.0, 60.0),
        M::ShoulderLength => (7.0, 25.0),
        M::BackLength => (28.0, 60.0),
        M::FrontLength => (22.0, 55.0),
        M::UpperArmGirth => (15.0, 60.0),
        M::ElbowGirth => (15.0, 45.0),
        M::WristGirth => (10.0, 30.0),
        M::ArmLength => (40.0, 90.0),
    }
}

enum Column {
    Target(MeasurementId),
    Alternative,
}

fn column(name: &str, figure: FigureType) -> Result<(Column, MeasurementId), SizeChartError> {
    let n = name.trim();
    let alias = match n {
        "upper_chest_girth" => Some((Column::Target(MeasurementId::ChestGirth), MeasurementId::ChestGirth)),
        "waist_girth_curvy" => Some(if figure == FigureType::Curvy {
            (Column::Target(MeasurementId::WaistGirth), MeasurementId::WaistGirth)
        } else {
            (Column::Alternative, MeasurementId::WaistGirth)
        }),
        "waist_girth_straight" => Some(if figure == FigureType::Straight {
            (Column::Target(MeasurementId::WaistGirth), MeasurementId::WaistGirth)
        } else {
            (Column::Alternative, MeasurementId::WaistGirth)
        }),
        _ => None,
    };
    if let Some(a) = alias {
        return Ok(a);
    }
    let id: MeasurementId = n.parse().map_err(|_| SizeChartError::UnknownColumn { column: n.to_owned() })?;
    Ok((Column::Target(id), id))
}

fn check_value(size: &str, col: &str, id: MeasurementId, value: f64, unit: Unit) -> Result<f64, SizeChartError> {
    if !value.is_finite() {
        return Err(SizeChartError::NotANumber { size: size.into(), column: col.into(), value: value.to_string() });
    }
    let (lo, hi) = plausible_range_cm(id);
    let cm = value * unit.metres() * 100.0;
    if cm >= lo && cm <= hi {
        return Ok(value * unit.metres());
    }
    let as_in = value * 2.54;
    if unit == Unit::Cm && as_in >= lo && as_in <= hi {
        return Err(SizeChartError::LikelyInches { size: size.into(), column: col.into(), value, as_cm: as_in });
    }
    Err(SizeChartError::OutOfRange { size: size.into(), column: col.into(), value_cm: cm, min_cm: lo, max_cm: hi })
}

struct RawRow {
    size: String,
    unit: Option<String>,
    values: Vec<(String, RawValue)>,
}

enum RawValue {
    Text(String),
    Number(f64, Option<String>),
}

fn finish(
    raw: Vec<RawRow>,
    chart_unit: Option<String>,
    opts: &SizeChartOptions,
    figure: FigureType,
    stated: Option<Sex>,
) -> Result<SizeChart, SizeChartError> {
    let mut women = false;
    if raw.is_empty() {
        return Err(SizeChartError::Empty);
    }
    if raw.len() > opts.max_sizes {
        return Err(SizeChartError::TooManySizes { count: raw.len(), max: opts.max_sizes });
    }
    let parse_unit = |size: &str, u: &str| -> Result<Unit, SizeChartError> {
        u.parse().map_err(|_| SizeChartError::UnknownUnit { size: size.into(), unit: u.into() })
    };
    let mut rows: Vec<SizeRow> = Vec::new();
    for r in raw {
        if rows.iter().any(|x| x.size == r.size) {
            return Err(SizeChartError::DuplicateSize { size: r.size });
        }
        let row_unit = match r.unit.as_deref().or(chart_unit.as_deref()) {
            Some(u) => parse_unit(&r.size, u)?,
            None => Unit::Cm,
        };
        let mut targets = BTreeMap::new();
        let mut alternatives = BTreeMap::new();
        for (col, v) in r.values {
            let (kind, id) = column(&col, figure)?;
            women |= matches!(id, MeasurementId::BustGirth | MeasurementId::UnderbustGirth)
                || col.trim().starts_with("waist_girth_");
            let (value, unit) = match v {
                RawValue::Text(t) if t.trim().is_empty() => continue,
                RawValue::Text(t) => {
                    let x: f64 = t.trim().parse().map_err(|_| SizeChartError::NotANumber {
                        size: r.size.clone(),
                        column: col.clone(),
                        value: t.clone(),
                    })?;
                    (x, row_unit)
                }
                RawValue::Number(x, u) => (
                    x,
                    match u {
                        Some(u) => parse_unit(&r.size, &u)?,
                        None => row_unit,
                    },
                ),
            };
            let m = check_value(&r.size, &col, id, value, unit)?;
            match kind {
                Column::Target(id) => {
                    targets.insert(id, m);
                }
                Column::Alternative => {
                    alternatives.insert(col.trim().to_owned(), m);
                }
            }
        }
        if targets.is_empty() {
            return Err(SizeChartError::EmptyRow { size: r.size });
        }
        rows.push(SizeRow { size: r.size, targets, alternatives });
    }
    let (sex, sex_source) = match stated.or(opts.sex) {
        Some(s) => (s, SexSource::Stated),
        None if women => (Sex::Female, SexSource::Inferred),
        None if rows.iter().any(|r| r.targets.contains_key(&MeasurementId::ChestGirth)) => {
            (Sex::Male, SexSource::Inferred)
        }
        None => (Sex::Female, SexSource::Default),
    };
    Ok(SizeChart { figure, sex, sex_source, rows })
}

fn parse_sex(text: &str) -> Result<Sex, SizeChartError> {
    match text.trim().to_ascii_lowercase().as_str() {
        "female" | "f" | "women" | "womens" | "women's" => Ok(Sex::Female),
        "male" | "m" | "men" | "mens" | "men's" => Ok(Sex::Male),
        _ => Err(SizeChartError::UnknownSex { sex: text.to_owned() }),
    }
}

/// A size chart as text, JSON when it opens with `{`, else CSV
/// ([`parse_json`], [`parse_csv`]): what a file holds.
///
/// # Errors
/// As [`parse_json`] or [`parse_csv`].
pub fn parse_text(text: &str, opts: &SizeChartOptions) -> Result<SizeChart, SizeChartError> {
    if text.trim_start().starts_with('{') {
        parse_json(text, opts)
    } else {
        parse_csv(text, opts)
    }
}

/// Parses a CSV size chart.
pub fn parse_csv(text: &str, opts: &SizeChartOptions) -> Result<SizeChart, SizeChartError> {
    let mut rdr = csv::ReaderBuilder::new().comment(Some(b'#')).trim(csv::Trim::All).from_reader(text.as_bytes());
    let headers: Vec<String> =
        rdr.headers().map_err(|e| SizeChartError::Syntax(e.to_string()))?.iter().map(str::to_owned).collect();
    let size_col = headers.iter().position(|h| h == "size").ok_or(SizeChartError::NoSizeColumn)?;
    let unit_col = headers.iter().position(|h| h == "unit");
    let sex_col = headers.iter().position(|h| h == "sex");
    let skip = |i: usize| i == size_col || Some(i) == unit_col || Some(i) == sex_col;
    let mut stated: Option<Sex> = None;
    for (i, h) in headers.iter().enumerate() {
        if !skip(i) {
            column(h, opts.figure)?;
        }
    }
    let mut raw = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| SizeChartError::Syntax(e.to_string()))?;
        if raw.len() >= opts.max_sizes {
            return Err(SizeChartError::TooManySizes { count: raw.len() + 1, max: opts.max_sizes });
        }
        let size = rec.get(size_col).unwrap_or("").to_owned();
        let unit = unit_col.and_then(|c| rec.get(c)).filter(|u| !u.is_empty()).map(str::to_owned);
        if let Some(cell) = sex_col.and_then(|c| rec.get(c)).filter(|x| !x.is_empty()) {
            let sex = parse_sex(cell)?;
            match stated {
                Some(first) if first != sex => {
                    return Err(SizeChartError::ConflictingSex { size, sex: cell.to_owned() })
                }
                _ => stated = Some(sex),
            }
        }
        let values = headers
            .iter()
            .enumerate()
            .filter(|(i, _)| !skip(*i))
            .map(|(i, h)| (h.clone(), RawValue::Text(rec.get(i).unwrap_or("").to_owned())))
            .collect();
        raw.push(RawRow { size, unit, values });
    }
    finish(raw, None, opts, opts.figure, stated)
}

/// A size chart as a JSON document (what [`parse_json`] reads): units per
/// chart or per row or per value (`cm`, `mm`, `m`, `in`), one object of
/// ISO 8559-1 measurements per size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SizeChartDocument {
    /// The unit of every value that does not say (`cm`, `mm`, `m` or `in`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<String>,
    /// Which ASTM waist column is the waist girth (women's charts).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub figure: Option<FigureType>,
    /// Whose bodies the chart describes; inferred from the columns when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sex: Option<Sex>,
    /// The sizes, in grading order.
    pub sizes: Vec<SizeChartDocumentRow>,
}

/// One size of a [`SizeChartDocument`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SizeChartDocumentRow {
    /// The size label (`8`, `M`, `38`).
    pub size: String,
    /// The unit of this row's values that do not say.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unit: Option<String>,
    /// Measurement (ISO 8559-1 name, e.g. `bust_girth`, or an ASTM waist
    /// column `waist_girth_curvy`) → value.
    pub measurements: BTreeMap<String, MeasurementValue>,
}

/// A measurement of a [`SizeChartDocumentRow`]: a number in the row's (or
/// chart's) unit, or a number with its own unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
#[serde(untagged)]
pub enum MeasurementValue {
    /// In the row's or chart's unit.
    Plain(f64),
    /// With its own unit.
    WithUnit {
        /// The value.
        value: f64,
        /// Its unit (`cm`, `mm`, `m` or `in`).
        unit: String,
    },
}

/// Parses a JSON size chart.
pub fn parse_json(text: &str, opts: &SizeChartOptions) -> Result<SizeChart, SizeChartError> {
    let c: SizeChartDocument = serde_json::from_str(text).map_err(|e| SizeChartError::Syntax(e.to_string()))?;
    if c.sizes.len() > opts.max_sizes {
        return Err(SizeChartError::TooManySizes { count: c.sizes.len(), max: opts.max_sizes });
    }
    let figure = c.figure.unwrap_or(opts.figure);
    let raw = c
        .sizes
        .into_iter()
        .map(|r| RawRow {
            size: r.size,
            unit: r.unit,
            values: r
                .measurements
                .into_iter()
                .map(|(k, v)| {
                    let v = match v {
                        MeasurementValue::Plain(x) => RawValue::Number(x, None),
                        MeasurementValue::WithUnit { value, unit } => RawValue::Number(value, Some(unit)),
                    };
                    (k, v)
                })
                .collect(),
        })
        .collect();
    finish(raw, c.unit, opts, figure, c.sex)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_chart_says_or_shows_whose_body_it_is() {
        // ASTM misses: bust and the figure-type waists make it a women's chart
        let astm = parse_csv(ASTM, &Default::default()).unwrap();
        assert_eq!((astm.sex, astm.sex_source), (Sex::Female, SexSource::Inferred));
        // a men's chart: chest, waist, hip, no bust
        let men = "size,unit,chest_girth,waist_girth,hip_girth\n40,in,40,34,40\n42,in,42,36,42\n";
        let m = parse_csv(men, &Default::default()).unwrap();
        assert_eq!((m.sex, m.sex_source), (Sex::Male, SexSource::Inferred));
        // stated in a column, or in JSON, wins
        let col = "size,unit,sex,chest_girth\n40,in,male,40\n42,in,male,42\n";
        assert_eq!(parse_csv(col, &Default::default()).unwrap().sex_source, SexSource::Stated);
        let j = r#"{"unit":"cm","sex":"female","sizes":[{"size":"S","measurements":{"chest_girth":84}}]}"#;
        let f = parse_json(j, &Default::default()).unwrap();
        assert_eq!((f.sex, f.sex_source), (Sex::Female, SexSource::Stated));
        // one chart, one sex
        let mixed = "size,unit,sex,chest_girth\n40,in,male,40\n42,in,female,42\n";
        assert_eq!(
            parse_csv(mixed, &Default::default()).unwrap_err(),
            SizeChartError::ConflictingSex { size: "42".into(), sex: "female".into() }
        );
        assert_eq!(
            parse_csv("size,sex,chest_girth\n40,x,100\n", &Default::default()).unwrap_err(),
            SizeChartError::UnknownSex { sex: "x".into() }
        );
        // nothing to tell by: women's, said to be the default
        let hips = parse_csv("size,unit,hip_girth\nS,cm,94\n", &Default::default()).unwrap();
        assert_eq!((hips.sex, hips.sex_source), (Sex::Female, SexSource::Default));
    }

    const ASTM: &str = include_str!("../../../../fixtures/size-charts/astm-d5585-11-misses-partial.csv");

    #[test]
    fn astm_chart_parses_with_both_figure_types() {
        let c = parse_csv(ASTM, &SizeChartOptions::default()).unwrap();
        assert_eq!(c.rows.len(), 12);
        let s8 = c.rows.iter().find(|r| r.size == "8").unwrap();
        assert!((s8.targets[&MeasurementId::BustGirth] - 36.25 * 0.0254).abs() < 1e-12);
        assert!((s8.targets[&MeasurementId::WaistGirth] - 28.0 * 0.0254).abs() < 1e-12);
        assert!((s8.targets[&MeasurementId::ChestGirth] - 35.875 * 0.0254).abs() < 1e-12);
        assert!(s8.alternatives.contains_key("waist_girth_straight"));
        let st = parse_csv(ASTM, &SizeChartOptions { figure: FigureType::Straight, ..Default::default() }).unwrap();
        assert!((st.rows[5].targets[&MeasurementId::WaistGirth] - 29.5 * 0.0254).abs() < 1e-12);
    }

    #[test]
    fn inches_declared_as_cm_is_caught() {
        let e = parse_csv("size,unit,bust_girth\nM,cm,36\n", &SizeChartOptions::default()).unwrap_err();
        assert!(
            matches!(e, SizeChartError::LikelyInches { ref size, ref column, .. } if size == "M" && column == "bust_girth"),
            "{e:?}"
        );
    }

    #[test]
    fn unknown_column_is_named() {
        let e = parse_csv("size,bust_girth,elbow_wobble\nM,90,3\n", &SizeChartOptions::default()).unwrap_err();
        assert_eq!(e, SizeChartError::UnknownColumn { column: "elbow_wobble".into() });
        let e =
            parse_json(r#"{"sizes":[{"size":"M","measurements":{"elbow_wobble":3}}]}"#, &SizeChartOptions::default())
                .unwrap_err();
        assert_eq!(e, SizeChartError::UnknownColumn { column: "elbow_wobble".into() });
    }

    #[test]
    fn other_bad_values() {
        let o = SizeChartOptions::default();
        assert!(matches!(parse_csv("size,bust_girth\nM,abc\n", &o), Err(SizeChartError::NotANumber { .. })));
        assert!(matches!(parse_csv("size,bust_girth\nM,NaN\n", &o), Err(SizeChartError::NotANumber { .. })));
        assert!(matches!(parse_csv("size,bust_girth\nM,900\n", &o), Err(SizeChartError::OutOfRange { .. })));
        assert!(matches!(
            parse_csv("size,unit,bust_girth\nM,furlong,90\n", &o),
            Err(SizeChartError::UnknownUnit { .. })
        ));
        assert!(matches!(parse_csv("bust_girth\n90\n", &o), Err(SizeChartError::NoSizeColumn)));
        assert!(matches!(parse_csv("size,bust_girth\nM,90\nM,92\n", &o), Err(SizeChartError::DuplicateSize { .. })));
        assert!(matches!(parse_csv("size,bust_girth\n", &o), Err(SizeChartError::Empty)));
        assert!(matches!(parse_csv("size,bust_girth\nM,\n", &o), Err(SizeChartError::EmptyRow { .. })));
        let many: String =
            std::iter::once("size,bust_girth\n".to_owned()).chain((0..41).map(|i| format!("{i},90\n"))).collect();
        assert!(matches!(parse_csv(&many, &o), Err(SizeChartError::TooManySizes { .. })));
    }

    #[test]
    fn json_with_per_value_units() {
        let c = parse_json(
            r#"{"unit":"in","figure":"straight","sizes":[{"size":"S","measurements":{"bust_girth":34,"waist_girth_straight":{"value":71,"unit":"cm"}}}]}"#,
            &SizeChartOptions::default(),
        )
        .unwrap();
        assert!((c.rows[0].targets[&MeasurementId::BustGirth] - 34.0 * 0.0254).abs() < 1e-12);
        assert!((c.rows[0].targets[&MeasurementId::WaistGirth] - 0.71).abs() < 1e-12);
    }
}
