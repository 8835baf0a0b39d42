//! Every typed error of the library mapped to its HTTP problem, in one
//! exhaustive `match` per error type: adding a variant anywhere fails to
//! compile here until it is given a status. Client errors name the field;
//! internal ones are logged and answered with a bare 500.

use axum::http::StatusCode;

use super::author::AuthorRequestError;
use super::problem::Problem;
use super::store::StoreError;
use super::work::WorkError;
use crate::body::derive::FeatureError;
use crate::body::frame::FrameError;
use crate::geom::repair::RepairError;
use crate::geom::topology::TopologyError;
use crate::io::garment::GarmentFileError;
use crate::io::gltf::GltfError;
use crate::io::landmarks::LandmarkFileError;
use crate::mannequin::fit::FitError;
use crate::mannequin::register::RegisterError;
use crate::mannequin::size_chart::SizeChartError;
use crate::pattern::assemble::PieceError;
use crate::pattern::export::rul::CreatedError;
use crate::pattern::flatten::FlattenError;
use crate::pattern::garment::PatternError;
use crate::pattern::panels::PanelError;
use crate::pipeline::PipelineError;
use crate::refine::clear::ClearError;
use crate::refine::subdivide::RefineError;
use crate::template::codec::CodecError;
use crate::template::edit::EditError;
use crate::template::format::TemplateError;
use crate::template::from_curves::FromCurvesError;
use crate::template::from_garment::FromGarmentError;
use crate::template::profile::ProfileError;
use crate::template::sketch::SketchError;
use grade3d_core::scan::ScanError;

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
            StoreError::Stale { .. } => {
                Problem::new(StatusCode::CONFLICT, "template-changed", "Template changed", e.to_string()).field("name")
            }
        }
    }
}

impl From<AuthorRequestError> for Problem {
    fn from(e: AuthorRequestError) -> Self {
        let detail = e.to_string();
        match &e {
            AuthorRequestError::File(f) => match f {
                GarmentFileError::Gltf(g) => gltf_problem(g, "garment", detail),
                GarmentFileError::Obj(_) => Problem::bad_request("garment-obj", detail).field("garment"),
                GarmentFileError::NotUtf8 => Problem::bad_request("garment-format", detail).field("garment"),
                GarmentFileError::TooLarge { .. } => {
                    Problem::new(StatusCode::PAYLOAD_TOO_LARGE, "garment-too-large", "Garment too large", detail)
                        .field("garment")
                }
            },
            AuthorRequestError::Units => Problem::unprocessable("garment-units", detail).field("units"),
            AuthorRequestError::Authoring(a) => match a {
                FromGarmentError::Panels(_) => Problem::unprocessable("garment-pieces", detail).field("garment"),
                FromGarmentError::NotADisc { .. } => {
                    Problem::unprocessable("garment-not-a-disc", detail).field("garment")
                }
                FromGarmentError::Option { .. } => Problem::bad_request("invalid-options", detail).field("options"),
                FromGarmentError::UnknownGirth { .. } => {
                    Problem::bad_request("invalid-options", detail).field("options.ease_at")
                }
                FromGarmentError::Body(_) => Problem::unprocessable("design-body", detail).field("body"),
                FromGarmentError::Surface(_) => Problem::unprocessable("garment-surface", detail).field("garment"),
                FromGarmentError::Simplify(_) => Problem::unprocessable("garment-contraction", detail).field("garment"),
                FromGarmentError::Codec(_) => Problem::unprocessable("authoring-failed", detail).field("garment"),
            },
            AuthorRequestError::Curves(c) => match c {
                FromCurvesError::NoPanel => Problem::unprocessable("curves-no-panel", detail).field("panels"),
                // the detail names the panel
                FromCurvesError::Patch { .. } => Problem::unprocessable("curves-patch", detail).field("panels"),
                FromCurvesError::Samples { .. } => {
                    Problem::bad_request("invalid-options", detail).field("curves.samples")
                }
                FromCurvesError::Join {
                    source: crate::template::garment_panels::PanelError::Tolerance { .. }, ..
                } => Problem::bad_request("invalid-options", detail).field("curves.join_tolerance_mm"),
                // the detail names the piece (an edge of three of its patches)
                FromCurvesError::Join { .. } => Problem::unprocessable("curves-join", detail).field("panels"),
            },
        }
    }
}

impl From<EditError> for Problem {
    /// A sketch edit the core refuses (issue #18 items 3–4): the stroke's own
    /// faults are 400s naming the field, every constraint a 422 whose slug
    /// names it (`constraint-c12-…`, `constraint-c13-…`, `constraint-c6-…`,
    /// `constraint-c8-…`, `constraint-symmetric`) and whose detail names the
    /// node, edge, panel or girth.
    fn from(e: EditError) -> Self {
        let detail = e.to_string();
        let c = |slug: &str, field: &str| Problem::unprocessable(slug, detail.clone()).field(field);
        match &e {
            EditError::Sketch(s) => match s {
                SketchError::View { .. } => Problem::bad_request("sketch-view", detail).field("view"),
                SketchError::ShortStroke { .. } | SketchError::NonFinite { .. } | SketchError::NoDirection => {
                    Problem::bad_request("sketch-stroke", detail).field("edit.stroke")
                }
                SketchError::NothingSelected { .. } => c("sketch-nothing-selected", "edit.stroke"),
                SketchError::EdgeOn => c("sketch-edge-on", "view"),
                // the edge table of a stored (validated) template
                SketchError::Index { .. } => internal(&detail),
            },
            EditError::NoNode { .. } => c("edit-no-such-node", "edit.node"),
            EditError::Codec(_) => c("template-cannot-be-edited", "name"),
            EditError::Profile { .. } => c("edit-profile", "edit.stroke"),
            EditError::Template(_) => c("edit-invalid-template", "edit"),
            EditError::Overridden { .. } => c("edit-overridden", "edit"),
            EditError::OutOfReach { .. } => c("edit-out-of-reach", "edit.stroke"),
            EditError::NoCounterpart { .. } => c("constraint-symmetric", "edit"),
            EditError::NodeInside { .. } => c("constraint-c12-inside-body", "edit.node"),
            EditError::ProfileInside { .. } => c("constraint-c12-inside-body", "edit.stroke"),
            EditError::NegativeEase { .. } => c("constraint-c12-negative-ease", "edit"),
            EditError::ProfileCrosses { .. } | EditError::OutlineCrosses { .. } => {
                c("constraint-c13-self-intersection", "edit")
            }
            EditError::EaseOutOfRange { .. } => c("constraint-c6-ease-range", "edit"),
            EditError::GirthOrder { .. } => c("constraint-c8-girth-order", "edit"),
            EditError::Refine(r) => match r {
                // the edited garment itself: a face the edit folded flat, a profile it broke
                RefineError::DegenerateFace { .. } | RefineError::Profile { .. } => c("edit-cannot-be-refined", "edit"),
                RefineError::Topology(_)
                | RefineError::IndexOutOfRange { .. }
                | RefineError::NonFinitePosition { .. }
                | RefineError::FixedFlags { .. }
                | RefineError::EdgeTable { .. }
                | RefineError::ProfileOnMissingEdge { .. }
                | RefineError::TooLarge { .. } => internal(&detail),
            },
            EditError::Mesh(_) => internal(&detail),
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
        TemplateError::Topology(TopologyError::NonManifoldEdge { .. } | TopologyError::NonManifoldVertex { .. }) => {
            ("template-non-manifold", "template.faces")
        }
        TemplateError::Topology(TopologyError::InconsistentOrientation { .. }) => {
            ("template-orientation", "template.faces")
        }
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
        | GltfError::NonFiniteTexCoord { .. }
        | GltfError::NoTriangles
        | GltfError::Mesh { .. }
        | GltfError::BadNormal { .. } => StatusCode::BAD_REQUEST,
        GltfError::LengthMismatch { .. }
        | GltfError::InvalidAttributeName { .. }
        | GltfError::NonFiniteOutput { .. }
        | GltfError::GlbWrite(_) => return internal(&detail),
    };
    Problem::new(status, "scan-invalid", "Invalid body scan", detail).field(field)
}

/// A scan that could not be repaired, framed or registered (issue #17):
/// the mesh's own faults a 400, what it is as a body a 422 naming the
/// figure; every variant of each step's error in one match.
fn scan_problem(e: &ScanError, detail: String) -> Problem {
    match e {
        ScanError::Repair(RepairError::Mesh(_)) => Problem::bad_request("scan-invalid", detail).field("scan"),
        ScanError::Repair(RepairError::NothingLeft { .. }) => {
            Problem::unprocessable("scan-nothing-left", detail).field("scan")
        }
        ScanError::Frame(f) => {
            let (slug, field) = match f {
                FrameError::Mesh(_) => ("scan-invalid", "scan"),
                FrameError::Axes { what: "up", .. } => ("scan-axes", "up"),
                FrameError::Axes { .. } => ("scan-axes", "facing"),
                FrameError::Units { .. } | FrameError::StatedUnits { .. } => ("scan-units", "units"),
                FrameError::Facing { .. } => ("scan-facing", "facing"),
                FrameError::Pose { .. } => ("scan-pose", "scan"),
            };
            Problem::unprocessable(slug, detail).field(field)
        }
        ScanError::Register(r) => match r {
            RegisterError::Residual { .. } | RegisterError::TooFewPairs { .. } => {
                Problem::unprocessable("scan-registration", detail).field("landmarks")
            }
            RegisterError::Landmark(_) => {
                Problem::unprocessable("scan-registration-landmark", detail).field("landmarks")
            }
            RegisterError::Model(_) => internal(&detail),
        },
        ScanError::Model(_) => internal(&detail),
        ScanError::Feature(f) => Problem::unprocessable(feature_slug(f), detail).field("landmarks"),
    }
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
        FeatureError::SwappedSides { .. } => "body-swapped-sides",
        FeatureError::PairHeight { .. } => "body-pair-height",
        FeatureError::OffSideLine { .. } => "body-off-side-line",
    }
}

impl From<WorkError> for Problem {
    fn from(e: WorkError) -> Self {
        let detail = e.to_string();
        match &e {
            WorkError::Model { .. }
            | WorkError::Render { .. }
            | WorkError::Export { .. }
            | WorkError::GarmentGlb { .. }
            | WorkError::FitReport(_)
            | WorkError::Serialise { .. } => internal(&detail),
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
            WorkError::ScanBody { source, .. } => scan_problem(source, detail),
            WorkError::TooManyVertices { .. } => {
                Problem::new(StatusCode::PAYLOAD_TOO_LARGE, "scan-too-many-vertices", "Body scan too large", detail)
                    .field("scan")
            }
            WorkError::Grade { source, .. } => match grade_failure(source) {
                GradeFailure::OnThisBody(slug) => Problem::unprocessable(slug, detail).field("templates"),
                GradeFailure::Template => {
                    Problem::unprocessable("template-cannot-be-graded", detail).field("templates")
                }
                GradeFailure::Internal => internal(&detail),
            },
            WorkError::Nest { .. } => Problem::unprocessable("grading-failed", detail).field("templates"),
            WorkError::UnknownBaseSize { .. } => Problem::bad_request("unknown-base-size", detail).field("base_size"),
        }
    }
}

/// Who a failed grade is down to (issue #16: the pipeline's errors mapped
/// to the leaf, so that an internal fault never leaves as a 422 carrying
/// internal detail).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum GradeFailure {
    /// The template cannot follow this body (its geometry): 422 with the slug.
    OnThisBody(&'static str),
    /// The template's own structure (the same on every body): 422, field `templates`.
    Template,
    /// Our fault (inputs that passed validation, options, numerics): a bare 500.
    Internal,
}

/// Every leaf of [`PipelineError`], classified in one exhaustive match per
/// error type (a new variant anywhere fails to compile here).
fn grade_failure(e: &PipelineError) -> GradeFailure {
    use GradeFailure::{Internal, OnThisBody, Template};
    let profile = |p: &ProfileError, slug: &'static str| match p {
        // geometry of this body: the profile's points collapse or run off
        ProfileError::NonFinitePoint { .. }
        | ProfileError::ZeroChord { .. }
        | ProfileError::ChordOverflow { .. }
        | ProfileError::ZeroNodeChord { .. }
        | ProfileError::NonFiniteNode { .. } => OnThisBody(slug),
        // the stored profile itself
        ProfileError::TooFewPoints { .. }
        | ProfileError::StoredLength { .. }
        | ProfileError::StoredIncomplete
        | ProfileError::StoredParam { .. }
        | ProfileError::NonFiniteTangent { .. } => Template,
    };
    match e {
        PipelineError::Decode(c) => match c {
            CodecError::MissingPoint { .. } | CodecError::SingularFrame { .. } => OnThisBody("template-does-not-fit"),
            CodecError::Profile { source, .. } => profile(source, "template-does-not-fit"),
            // the draft of a validated template, and a stored template that no longer validates
            CodecError::Draft(_) | CodecError::Template(_) => Internal,
        },
        PipelineError::Refine(r) => match r {
            RefineError::Profile { .. } => OnThisBody("refine-failed"),
            // the decoded mesh of a validated template: our fault when it is not a mesh
            RefineError::Topology(_)
            | RefineError::IndexOutOfRange { .. }
            | RefineError::DegenerateFace { .. }
            | RefineError::NonFinitePosition { .. }
            | RefineError::FixedFlags { .. }
            | RefineError::EdgeTable { .. }
            | RefineError::ProfileOnMissingEdge { .. }
            | RefineError::TooLarge { .. } => Internal,
        },
        PipelineError::Clear(ClearError::Profile { source, .. }) => profile(source, "garment-cannot-clear-body"),
        PipelineError::Pattern(p) => match p {
            PatternError::Panel(panel) => match panel {
                PanelError::NotADisc { .. }
                | PanelError::SeamOffOutline { .. }
                | PanelError::SeamNotChained { .. }
                | PanelError::BadDart { .. }
                | PanelError::UnknownPanel { .. } => Template,
                PanelError::FaceCount { .. } => Internal,
            },
            PatternError::Flatten { source, .. } => match source {
                FlattenError::NonFinite { .. } | FlattenError::DegenerateTriangle { .. } => {
                    OnThisBody("pattern-failed")
                }
                // the cut panels are ours: a panel that is not a disc mesh, bad options, numerics
                FlattenError::Empty
                | FlattenError::IndexOutOfRange { .. }
                | FlattenError::Topology(_)
                | FlattenError::Disconnected { .. }
                | FlattenError::NotADisc { .. }
                | FlattenError::SeamVertex { .. }
                | FlattenError::SewnRatio { .. }
                | FlattenError::InvalidOption { .. }
                | FlattenError::Factorisation(_) => Internal,
            },
            PatternError::Piece(piece) => match piece {
                PieceError::GrainOffPanel { .. } => Template,
                PieceError::DegenerateGrain { .. } => OnThisBody("pattern-failed"),
                PieceError::UvCount { .. } => Internal,
            },
            // a run's plan comes from the same refinement of the same template
            PatternError::CarriedDart { .. } => Internal,
        },
        // the service's own configuration
        PipelineError::ShadowedOption { .. } => Internal,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grade(source: PipelineError) -> Problem {
        Problem::from(WorkError::Grade { template: "trousers".into(), size: "8".into(), source })
    }

    #[test]
    fn an_internal_fault_of_a_grade_is_a_bare_500_and_a_body_it_cannot_follow_a_422() {
        // regression (issue #16): every pipeline error left as a 422 with its text, internal
        // faults included (here: the refinement's own edge table)
        let p = grade(PipelineError::Refine(RefineError::EdgeTable { edges: 12, profiles: 11 }));
        assert_eq!(p.status, 500);
        assert!(!p.detail.contains("profile") && !p.detail.contains("12"), "{}", p.detail);
        let p = grade(PipelineError::Pattern(PatternError::Flatten {
            panel: "front".into(),
            source: FlattenError::Factorisation("not positive definite".into()),
        }));
        assert_eq!(p.status, 500);
        assert!(!p.detail.contains("definite"), "{}", p.detail);
        let p = grade(PipelineError::ShadowedOption { nested: "refine.levels", top: "levels" });
        assert_eq!(p.status, 500);
        // the body: 422 naming what does not fit
        let p =
            grade(PipelineError::Clear(ClearError::Profile { edge: 3, source: ProfileError::ZeroChord { index: 2 } }));
        assert_eq!((p.status, p.kind.as_str()), (422, "/problems/garment-cannot-clear-body"));
        assert!(p.detail.contains("edge 3"), "{}", p.detail);
        // the template's own structure: 422, the same on every body
        let p = grade(PipelineError::Pattern(PatternError::Panel(PanelError::UnknownPanel {
            seam: "side".into(),
            panel: "nope".into(),
        })));
        assert_eq!((p.status, p.kind.as_str()), (422, "/problems/template-cannot-be-graded"));
        assert_eq!(p.field.as_deref(), Some("templates"));
    }
}
