//! Every typed error of the library mapped to its HTTP problem, in one
//! exhaustive `match` per error type: adding a variant anywhere fails to
//! compile here until it is given a status. Client errors name the field;
//! internal ones are logged and answered with a bare 500.

use axum::http::StatusCode;

use super::problem::Problem;
use super::store::StoreError;
use super::work::WorkError;
use crate::body::derive::FeatureError;
use crate::io::gltf::GltfError;
use crate::io::landmarks::LandmarkFileError;
use crate::mannequin::fit::FitError;
use crate::mannequin::size_chart::SizeChartError;
use crate::pattern::export::rul::CreatedError;
use crate::pipeline::PipelineError;
use crate::template::format::TemplateError;

fn internal(what: &dyn std::fmt::Display) -> Problem {
    tracing::error!(error = %what, "internal error");
    Problem::internal()
}

impl From<StoreError> for Problem {
    fn from(e: StoreError) -> Self {
        match &e {
            StoreError::Database { .. } => internal(&e),
            StoreError::Invalid(t) => template_problem(t),
            StoreError::NotFound { .. } => Problem::not_found(e.to_string()).field("name"),
            StoreError::Exists { .. } => {
                Problem::new(StatusCode::CONFLICT, "template-exists", "Template exists", e.to_string()).field("name")
            }
            StoreError::NameMismatch { .. } => Problem::bad_request("name-mismatch", e.to_string()).field("name"),
        }
    }
}

/// A template document the library refuses.
pub fn template_problem(e: &TemplateError) -> Problem {
    let (slug, field) = match e {
        TemplateError::Syntax { .. } => ("template-syntax", "template"),
        TemplateError::Schema { .. } => ("template-schema", "template"),
        TemplateError::NotATemplate { .. } => ("not-a-template", "template.schema"),
        TemplateError::FutureSchema { .. } => ("template-future-schema", "template.schema_version"),
        TemplateError::FutureVocabulary { .. } => ("template-future-vocabulary", "template.vocabulary"),
        TemplateError::Empty { .. } => ("template-empty", "template.faces"),
        TemplateError::NonFinite { .. } => ("template-non-finite", "template.nodes"),
        TemplateError::BadEdge { .. } => ("template-bad-edge", "template.edges"),
        TemplateError::MissingEdge { .. } => ("template-missing-edge", "template.faces"),
        TemplateError::InconsistentDirections { .. } => ("template-edge-directions", "template.faces"),
        TemplateError::NonManifoldEdge { .. } => ("template-non-manifold", "template.faces"),
        TemplateError::InconsistentOrientation { .. } => ("template-orientation", "template.faces"),
        TemplateError::BadReference { .. } => ("template-bad-reference", "template"),
    };
    Problem::unprocessable(slug, e.to_string()).field(field)
}

/// A size chart the library refuses.
pub fn chart_problem(e: &SizeChartError) -> Problem {
    let slug = match e {
        SizeChartError::Syntax { .. } => "chart-syntax",
        SizeChartError::UnknownColumn { .. } => "chart-unknown-column",
        SizeChartError::NoSizeColumn => "chart-no-size-column",
        SizeChartError::UnknownUnit { .. } => "chart-unknown-unit",
        SizeChartError::NotANumber { .. } => "chart-not-a-number",
        SizeChartError::OutOfRange { .. } => "chart-out-of-range",
        SizeChartError::LikelyInches { .. } => "chart-likely-inches",
        SizeChartError::Empty => "chart-empty",
        SizeChartError::TooManySizes { .. } => "chart-too-many-sizes",
        SizeChartError::DuplicateSize { .. } => "chart-duplicate-size",
        SizeChartError::EmptyRow { .. } => "chart-empty-row",
        SizeChartError::ConflictingSex { .. } => "chart-conflicting-sex",
        SizeChartError::UnknownSex { .. } => "chart-unknown-sex",
    };
    Problem::bad_request(slug, e.to_string()).field("chart")
}

/// The problem of a `created` stamp that cannot be read (400, field `created`).
pub fn created_problem(e: &CreatedError) -> Problem {
    let slug = match e {
        CreatedError::NotRfc3339 { .. } | CreatedError::OutOfRange(_) => "invalid-created",
    };
    Problem::bad_request(slug, e.to_string()).field("created")
}

fn gltf_problem(e: &GltfError, field: &str, detail: String) -> Problem {
    let status = match e {
        GltfError::InputTooLarge { .. }
        | GltfError::TooManyVertices { .. }
        | GltfError::TooManyTriangles { .. }
        | GltfError::GlbTooLarge { .. } => StatusCode::PAYLOAD_TOO_LARGE,
        GltfError::GlbTruncated { .. }
        | GltfError::MalformedGlb { .. }
        | GltfError::Json { .. }
        | GltfError::DanglingIndex { .. }
        | GltfError::NodeHierarchy { .. }
        | GltfError::NonFiniteTransform { .. }
        | GltfError::ExternalUri { .. }
        | GltfError::BadDataUri { .. }
        | GltfError::MissingBufferData { .. }
        | GltfError::BufferTooShort { .. }
        | GltfError::BufferViewOutOfBounds { .. }
        | GltfError::UnsupportedMode { .. }
        | GltfError::MissingPosition { .. }
        | GltfError::WrongAccessorType { .. }
        | GltfError::SparseAccessor { .. }
        | GltfError::MissingBufferView { .. }
        | GltfError::BadStride { .. }
        | GltfError::AccessorOutOfBounds { .. }
        | GltfError::IndexCount { .. }
        | GltfError::IndexOutOfRange { .. }
        | GltfError::NonFinitePosition { .. }
        | GltfError::NoTriangles
        | GltfError::Mesh { .. }
        | GltfError::BadNormal { .. } => StatusCode::BAD_REQUEST,
        GltfError::LengthMismatch { .. }
        | GltfError::InvalidAttributeName { .. }
        | GltfError::NonFiniteOutput { .. } => return internal(&detail),
    };
    Problem::new(status, "scan-invalid", "Invalid body scan", detail).field(field)
}

fn feature_slug(e: &FeatureError) -> &'static str {
    match e {
        FeatureError::Mesh { .. } => "body-mesh",
        FeatureError::BodySize { .. } => "body-size",
        FeatureError::MissingLandmarks { .. } => "body-missing-landmarks",
        FeatureError::NonFiniteLandmark { .. } => "body-non-finite-landmark",
        FeatureError::LandmarkOffSurface { .. } => "body-landmark-off-surface",
        FeatureError::BadCurve { .. } => "body-bad-curve",
        FeatureError::NoSection { .. } => "body-no-section",
        FeatureError::CurvesDoNotCross { .. } => "body-curves-do-not-cross",
        FeatureError::DegenerateFrame { .. } => "body-degenerate-frame",
        FeatureError::OffMidline { .. } => "body-landmark-off-midline",
        FeatureError::ImplausibleGirth { .. } => "body-implausible-girth",
        FeatureError::LandmarkHeight { .. } => "body-landmark-height",
    }
}

impl From<WorkError> for Problem {
    fn from(e: WorkError) -> Self {
        let detail = e.to_string();
        match &e {
            WorkError::Model { .. }
            | WorkError::Render { .. }
            | WorkError::Export { .. }
            | WorkError::GarmentGlb { .. } => internal(&detail),
            WorkError::Fit { source, .. } => match source {
                FitError::Mannequin { .. } | FitError::Landmark { .. } => internal(&detail),
                FitError::Feature(f) => Problem::unprocessable(feature_slug(f), detail).field("chart"),
                FitError::Unsupported { .. } => Problem::unprocessable("chart-unsupported", detail).field("chart"),
            },
            WorkError::Scan { source, .. } => gltf_problem(source, "scan", detail),
            WorkError::Landmarks { source, .. } => {
                let slug = match source {
                    LandmarkFileError::Syntax { .. } => "landmarks-syntax",
                    LandmarkFileError::UnknownPoint { .. } => "landmarks-unknown-point",
                    LandmarkFileError::UnknownCurve { .. } => "landmarks-unknown-curve",
                    LandmarkFileError::NonFinite { .. } => "landmarks-non-finite",
                    LandmarkFileError::FutureVocabulary { .. } => "landmarks-future-vocabulary",
                    LandmarkFileError::Units { .. } => "landmarks-units",
                    LandmarkFileError::ShortCurve { .. } => "landmarks-short-curve",
                };
                Problem::bad_request(slug, detail).field("landmarks")
            }
            WorkError::Feature { source, .. } => {
                Problem::unprocessable(feature_slug(source), detail).field("landmarks")
            }
            WorkError::TooManyVertices { .. } => {
                Problem::new(StatusCode::PAYLOAD_TOO_LARGE, "scan-too-many-vertices", "Body scan too large", detail)
                    .field("scan")
            }
            WorkError::Grade { source, .. } => {
                let slug = match source {
                    PipelineError::Decode { .. } => "template-does-not-fit",
                    PipelineError::Refine { .. } => "refine-failed",
                    PipelineError::Clear { .. } => "garment-cannot-clear-body",
                    PipelineError::Pattern { .. } => "pattern-failed",
                };
                Problem::unprocessable(slug, detail).field("templates")
            }
            WorkError::Nest { .. } => Problem::unprocessable("grading-failed", detail).field("templates"),
            WorkError::UnknownBaseSize { .. } => Problem::bad_request("unknown-base-size", detail).field("base_size"),
        }
    }
}
