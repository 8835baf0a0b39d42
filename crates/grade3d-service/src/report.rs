//! The fit report of a flow (`report.json`, and `report` in every grading
//! result and finished job): typed, so that its schema in `openapi.yaml` is
//! generated from the same types that write it (issue #16, item 4).
//!
//! A flow's report is a [`SizeChartReport`] (one entry per size: the
//! mannequin's residuals and the garments) or a [`BodiesReport`] (one entry
//! per body: its measurements and the garments); each garment's entry is
//! the core's [`GarmentReport`] ([`grade3d_core::report`]). Written as JSON
//! with every object's keys in lexicographic order (through
//! [`serde_json::Value`]), as it has been since issue #6.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use utoipa::ToSchema;

use grade3d_core::body::derive::FeatureWarning;
use grade3d_core::mannequin::fit::Residual;
use grade3d_core::mannequin::size_chart::{FigureType, Sex, SexSource};
use grade3d_core::pattern::true_up::TrueReport;
use grade3d_core::report::GarmentReport;
use grade3d_core::scan::ScanReport;

use crate::store::Entry;

/// Which flow made a report.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, ToSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Flow {
    /// A size chart: one mannequin per size.
    SizeChart,
    /// One body scan.
    Scan,
    /// Several bodies (a batch job's `bodies`).
    Bodies,
    /// A sketch edit's preview (`POST /v1/templates/{name}/edits`).
    SketchEdit,
}

/// One chart measurement as the fitted mannequin has it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ResidualReport {
    /// The chart's value, m.
    pub target_m: f64,
    /// The mannequin's, m.
    pub achieved_m: f64,
    /// achieved − target, mm.
    pub error_mm: f64,
}

impl From<&Residual> for ResidualReport {
    fn from(r: &Residual) -> Self {
        Self { target_m: r.target_m, achieved_m: r.achieved_m, error_mm: r.error_mm() }
    }
}

/// The mannequin of one size.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct MannequinReport {
    /// Per chart measurement (ISO 8559-1 name), the fit's residual.
    pub residuals: BTreeMap<String, ResidualReport>,
    /// What derivation accepted but a person should look at.
    pub warnings: Vec<FeatureWarning>,
}

/// One size of a chart.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SizeReport {
    /// The size label, as in the chart.
    pub size: String,
    /// Its mannequin.
    pub mannequin: MannequinReport,
    /// Every template on it, in request order.
    pub garments: Vec<GarmentReport>,
}

/// The report of the size-chart flow.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct SizeChartReport {
    /// `size-chart`.
    pub flow: Flow,
    /// Whose bodies the chart describes.
    pub sex: Sex,
    /// Whether `sex` was stated or inferred from the columns.
    pub sex_source: SexSource,
    /// The figure type of ASTM waist columns (women's charts; null for men's).
    pub figure: Option<FigureType>,
    /// The grade rules' base size.
    pub base_size: String,
    /// The templates graded, with the versions used.
    pub templates: Vec<Entry>,
    /// Whether the bodies were obstacles (a GPU context, or its CPU driver, rendered their depth maps).
    pub collision_checked: bool,
    /// Per template, what truing the nest at its corners moved.
    pub nest_truing: BTreeMap<String, TrueReport>,
    /// Per size, in the chart's order.
    pub sizes: Vec<SizeReport>,
}

/// One body of the scan or bodies flow.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct BodyReport {
    /// The body's name in the request (`scan` for the scan flow).
    pub body: String,
    /// Its measurements (ISO 8559-1 names), m.
    pub measurements_m: BTreeMap<String, f64>,
    /// What derivation accepted but a person should look at.
    pub warnings: Vec<FeatureWarning>,
    /// How the scan was read (issue #17): repair counts, units, axes and
    /// pose, landmarks supplied and found, the registration's residual.
    pub scan: ScanReport,
    /// Every template on it, in request order.
    pub garments: Vec<GarmentReport>,
}

/// The report of the scan flow and of a batch job's bodies.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct BodiesReport {
    /// `scan` (one body) or `bodies`.
    pub flow: Flow,
    /// The templates graded, with the versions used.
    pub templates: Vec<Entry>,
    /// Whether the bodies were obstacles.
    pub collision_checked: bool,
    /// Per body, in request order.
    pub bodies: Vec<BodyReport>,
}

/// A flow's fit report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(untagged)]
pub enum Report {
    /// A size chart's.
    SizeChart(SizeChartReport),
    /// A scan's or a batch of bodies'.
    Bodies(BodiesReport),
    /// A sketch edit's (its preview's result).
    SketchEdit(crate::edit::EditReport),
}
