//! The HTTP contract, generated from the code (issue #16, item 4).
//!
//! Every route of [`crate::app`] is a handler annotated with
//! `#[utoipa::path]` and registered through `utoipa_axum`'s
//! `OpenApiRouter` ([`crate::routes`]): the router and the OpenAPI
//! document come from the same list, so no route can be served without
//! being documented. The request, response and report types are the serde
//! structs below (and [`crate::report`], [`grade3d_core::report`]) with
//! `utoipa` schemas; [`openapi_yaml`] writes the document that is committed
//! as `openapi.yaml` (`grade3d openapi > openapi.yaml`), and a test fails
//! when the committed file differs from it.
//!
//! Artefact downloads answer their own media type (`model/gltf-binary`,
//! `image/vnd.dxf`, `image/svg+xml`, …), or `application/octet-stream`
//! when the client accepts only that; the latter is listed first, so that a
//! generated client reads any artefact as bytes.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use utoipa::openapi::schema::Schema;
use utoipa::openapi::security::{HttpAuthScheme, HttpBuilder, SecurityScheme};
use utoipa::openapi::{ContentBuilder, HeaderBuilder, Ref, RefOr, Response, ResponseBuilder};
use utoipa::{Modify, OpenApi, ToResponse, ToSchema};

use grade3d_core::mannequin::size_chart::{FigureType, SizeChartDocument};

use crate::jobs::JobState;
use crate::problem::{Problem, PROBLEM_JSON};
use crate::report::Report;
use crate::store::Entry;

/// The path of an artefact download: the result's or job's id and the
/// artefact's name (one of the enumerated forms).
#[derive(Debug, Clone, PartialEq, Deserialize, utoipa::IntoParams)]
#[into_params(parameter_in = Path)]
pub struct ArtefactPath {
    /// The result's or job's content address.
    pub id: String,
    /// File name: `{template}-{size}.pattern.svg|.pattern.dxf|.pattern.accumark.dxf|.pattern.json|.garment.glb`,
    /// `{template}.nest.svg|.nest.dxf|.nest.accumark.dxf|.nest.rul|.rules.csv`, `report.json`.
    #[param(
        pattern = r"^(report\.json|[A-Za-z0-9._-]+\.(pattern\.svg|pattern\.dxf|pattern\.accumark\.dxf|pattern\.json|garment\.glb|nest\.svg|nest\.dxf|nest\.accumark\.dxf|nest\.rul|rules\.csv))$"
    )]
    pub artefact: String,
}

/// `GET /readyz`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Ready {
    /// Always true (a service that is not ready answers 503).
    pub ready: bool,
    /// Live templates.
    pub templates: usize,
    /// What draws the depth maps: the wgpu adapter, or the CPU rasteriser
    /// and why; null when there are none (grading then runs without
    /// collision avoidance).
    pub gpu: Option<String>,
}

/// A size chart: a JSON document, or CSV text (a `size` column, optional
/// `unit` and `sex` columns, one column per ISO 8559-1 measurement).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(untagged)]
#[schema(as = SizeChart)]
pub enum SizeChartInput {
    /// A JSON size chart.
    Document(SizeChartDocument),
    /// A CSV size chart.
    Csv(String),
}

/// Body of `POST /v1/grade/size-chart` as JSON.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[serde(deny_unknown_fields)]
pub struct SizeChartRequest {
    /// Template names (at most the configured limit, 8 by default).
    pub templates: Vec<String>,
    /// The chart.
    #[schema(value_type = SizeChartInput)]
    pub chart: serde_json::Value,
    /// The grade rules' base size (default: the middle row).
    #[serde(default)]
    pub base_size: Option<String>,
    /// The figure type of ASTM waist columns, where the chart does not say.
    #[serde(default)]
    pub figure: Option<FigureType>,
    /// RFC 3339 date-time written (in UTC) as the `.RUL` files' `CREATION
    /// DATE:` and `CREATION TIME:`; part of the result's content address.
    /// Default: when the result is computed (a cached result keeps its
    /// stamp); give it for byte-identical artefacts from any server or from
    /// `grade3d grade --created`.
    #[serde(default)]
    #[schema(format = DateTime)]
    pub created: Option<String>,
}

/// Query of `POST /v1/grade/size-chart` with a CSV body.
#[derive(Debug, Clone, PartialEq, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
#[into_params(parameter_in = Query)]
pub struct SizeChartQuery {
    /// With a CSV body, comma-separated template names.
    pub templates: Option<String>,
    /// With a CSV body, the base size of the grade rules (default the middle row).
    pub base_size: Option<String>,
    /// With a CSV body, the figure type for ASTM waist columns.
    pub figure: Option<FigureType>,
    /// With a CSV body, the `.RUL` files' creation stamp (as `SizeChartRequest.created`).
    #[param(format = DateTime)]
    pub created: Option<String>,
}

/// Query of `GET /v1/templates/{name}`.
#[derive(Debug, Clone, PartialEq, Deserialize, utoipa::IntoParams)]
#[serde(deny_unknown_fields)]
#[into_params(parameter_in = Query)]
pub struct VersionQuery {
    /// A version by number (default: the live one).
    pub version: Option<u32>,
}

/// Multipart body of `POST /v1/grade/scan`.
#[derive(Debug, ToSchema)]
pub struct ScanUpload {
    /// The scan: GLB, or glTF with embedded buffers, as the scanner gives it: metres, centimetres or
    /// millimetres, +Y or +Z up, any facing (each found unless stated), holes, degenerate and duplicate
    /// triangles (repaired and counted in the report's `scan.repair`).
    #[schema(value_type = String, format = Binary)]
    pub scan: Vec<u8>,
    /// The landmarks document (JSON; its schema: `Landmarks`, the IDs listed by `GET /v1/vocabulary`),
    /// optional: landmarks it lacks are read off the body model registered to the scan, and the report's
    /// `scan.registration` gives the residual and a confidence per landmark.
    pub landmarks: Option<String>,
    /// The scan's units: `m`, `cm` or `mm` (default: found from its height).
    pub units: Option<grade3d_core::body::frame::Units>,
    /// Its up axis: `+y` or `+z` (default: the longer of the two extents).
    pub up: Option<grade3d_core::body::frame::Axis>,
    /// The direction the body faces, in the scan's axes (default: where its feet point).
    pub facing: Option<grade3d_core::body::frame::Axis>,
    /// A template name, or several comma-separated.
    pub template: String,
}

/// One artefact of a result or job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct ArtefactLink {
    /// File name.
    pub name: String,
    /// Media type.
    pub media_type: String,
    /// Size, bytes.
    pub bytes: usize,
    /// Where to download it.
    pub href: String,
}

/// The answer of the grading flows and `GET /v1/results/{id}`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct GradeResult {
    /// Content address of the inputs.
    pub id: String,
    /// The flow: `size-chart` or `scan`.
    pub flow: crate::report::Flow,
    /// The result's URL.
    pub href: String,
    /// Scan results: seconds they are kept.
    pub expires_in_s: Option<u64>,
    /// The fit report.
    #[schema(value_type = Report)]
    pub report: serde_json::Value,
    /// Wall time per stage, ms.
    pub timings_ms: BTreeMap<String, f64>,
    /// Every artefact.
    pub artefacts: Vec<ArtefactLink>,
    /// Whether it was served from the cache.
    pub cached: bool,
}

/// Where a job is in its run. Units are the chart's sizes or the job's
/// bodies; `total` stays the same from submission to the end (`done` =
/// `total` once done).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct JobProgress {
    /// The stage now (`queued`, `fit`, `body`, `refine`, `export`, `done`, `failed`).
    pub stage: String,
    /// Units done.
    pub done: usize,
    /// Units in all.
    pub total: usize,
}

/// A batch job.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
#[schema(as = Job)]
pub struct JobView {
    /// Content address of its inputs.
    pub id: String,
    /// The job's URL.
    pub href: String,
    /// Its state.
    pub state: JobState,
    /// Its progress.
    pub progress: JobProgress,
    /// The templates, with the versions fixed at submission.
    pub templates: Vec<Entry>,
    /// The problem of a failed job.
    pub error: Option<Problem>,
    /// The fit report of a finished job.
    #[schema(value_type = Option<Report>)]
    pub report: Option<serde_json::Value>,
    /// Wall time per stage, ms.
    pub timings_ms: BTreeMap<String, f64>,
    /// Its artefacts, once done.
    pub artefacts: Vec<ArtefactLink>,
}

/// A problem response of the given description.
fn problem(description: &str) -> Response {
    ResponseBuilder::new()
        .description(description)
        .content(PROBLEM_JSON, ContentBuilder::new().schema(Some(Ref::from_schema_name("Problem"))).build())
        .build()
}

macro_rules! problem_responses {
    ($($name:ident: $desc:literal),+ $(,)?) => {
        $(
            #[doc = $desc]
            pub struct $name;
            impl<'s> ToResponse<'s> for $name {
                fn response() -> (&'s str, RefOr<Response>) {
                    (stringify!($name), problem($desc).into())
                }
            }
        )+
    };
}

problem_responses! {
    BadRequest: "Malformed or invalid input; `field` names it.",
    Unauthorized: "A missing or invalid API key.",
    Forbidden: "Writes are disabled (no API key configured).",
    NotFound: "No such template, version, result, job or artefact.",
    Conflict: "The template exists (replace it with PUT), or it changed while an edit was made (edit it again).",
    TooLarge: "The body (or a scan's vertex count) exceeds the configured limit.",
    UnsupportedMedia: "The Content-Type is not one this route reads.",
    Unprocessable: "Well-formed input the domain refuses (an unknown template, a body that is not a body, a template that does not fit, a sketch edit that breaks a constraint).",
    Internal: "An internal error (nothing internal is disclosed).",
}

macro_rules! problem_sets {
    ($($(#[$doc:meta])* $name:ident: [$($code:literal => $response:ident),+]),+ $(,)?) => {
        $(
            $(#[$doc])*
            pub struct $name;
            impl utoipa::IntoResponses for $name {
                fn responses() -> BTreeMap<String, RefOr<Response>> {
                    [$(($code, stringify!($response))),+]
                        .into_iter()
                        .map(|(code, name)| (code.to_owned(), RefOr::Ref(Ref::from_response_name(name))))
                        .collect()
                }
            }
        )+
    };
}

problem_sets! {
    /// The problems of a read by id or name: 401, 403, 404, 500.
    ReadProblems: ["401" => Unauthorized, "403" => Forbidden, "404" => NotFound, "500" => Internal],
    /// The problems of a template write: 400, 401, 403, 413, 422, 503, 500.
    WriteProblems: [
        "400" => BadRequest, "401" => Unauthorized, "403" => Forbidden, "413" => TooLarge,
        "422" => Unprocessable, "503" => Unavailable, "500" => Internal
    ],
    /// The problems of a grading flow or a job submission: 400, 401, 403,
    /// 413, 415, 422, 503, 500.
    FlowProblems: [
        "400" => BadRequest, "401" => Unauthorized, "403" => Forbidden, "413" => TooLarge,
        "415" => UnsupportedMedia, "422" => Unprocessable, "503" => Unavailable, "500" => Internal
    ],
}

/// Busy (the work queue is full), over the time limit, or not ready; retry
/// after `Retry-After` seconds.
pub struct Unavailable;

impl<'s> ToResponse<'s> for Unavailable {
    fn response() -> (&'s str, RefOr<Response>) {
        let mut r = problem(
            "Busy (the work queue is full), over the time limit, or not ready; retry after `Retry-After` seconds.",
        );
        r.headers.insert(
            "Retry-After".into(),
            HeaderBuilder::new()
                .schema(utoipa::openapi::ObjectBuilder::new().schema_type(utoipa::openapi::schema::Type::String))
                .description(Some("Seconds to wait before retrying."))
                .build(),
        );
        ("Unavailable", r.into())
    }
}

/// A cached result's or a finished job's artefact, with its media type.
pub struct ArtefactBytes;

impl<'s> ToResponse<'s> for ArtefactBytes {
    fn response() -> (&'s str, RefOr<Response>) {
        use utoipa::openapi::schema::{ObjectBuilder, Type};
        let binary =
            || {
                ContentBuilder::new()
                    .schema(Some(ObjectBuilder::new().schema_type(Type::String).format(Some(
                        utoipa::openapi::SchemaFormat::KnownFormat(utoipa::openapi::KnownFormat::Binary),
                    ))))
                    .build()
            };
        let text = || ContentBuilder::new().schema(Some(ObjectBuilder::new().schema_type(Type::String))).build();
        let r = ResponseBuilder::new()
            .description(
                "The artefact's bytes, with its media type (`application/octet-stream` when the request \
                 accepts only that). `.dxf`: AAMA/ASTM D6673; `.accumark.dxf`: Gerber AccuMark's strict R12; \
                 `.nest.rul`: the grade rules the nest DXF's `# n` texts number.",
            )
            .content("application/octet-stream", binary())
            .content("model/gltf-binary", binary())
            .content("image/vnd.dxf", text())
            .content("image/svg+xml", text())
            .content("text/csv", text())
            .content("text/plain", text())
            .content("application/json", ContentBuilder::new().schema(Some(ObjectBuilder::new())).build())
            .header(
                "Content-Disposition",
                HeaderBuilder::new()
                    .schema(ObjectBuilder::new().schema_type(Type::String))
                    .description(Some("`attachment; filename=\"<name>\"`"))
                    .build(),
            )
            .build();
        ("Artefact", r.into())
    }
}

/// The template document's schema, as its published JSON Schema
/// (`templates/schema/garment-template.schema.json`, the one
/// `Template::from_json` checks) says: its `$defs` hoisted into the
/// components (`TemplateVec3`), `const` written as a one-value `enum`
/// (the same constraint, in the keywords utoipa's model keeps).
pub struct TemplateDocument;

/// The template schema as OpenAPI components: `Template` and its `$defs`
/// (`TemplateVec3`, …), with its `$ref`s rewritten to them.
fn template_components() -> Result<Vec<(String, RefOr<Schema>)>, String> {
    let mut doc: serde_json::Value =
        serde_json::from_str(grade3d_core::template::format::SCHEMA_JSON).map_err(|e| e.to_string())?;
    let obj = doc.as_object_mut().ok_or("the template schema is not an object")?;
    obj.remove("$schema");
    obj.remove("$id");
    let defs = obj.remove("$defs").and_then(|d| d.as_object().cloned()).unwrap_or_default();
    let component = |name: &str| format!("Template{}{}", name[..1].to_uppercase(), &name[1..]);
    fn rewrite(v: &mut serde_json::Value, component: &dyn Fn(&str) -> String) {
        match v {
            serde_json::Value::Object(map) => {
                if let Some(serde_json::Value::String(r)) = map.get_mut("$ref") {
                    if let Some(name) = r.strip_prefix("#/$defs/") {
                        *r = format!("#/components/schemas/{}", component(name));
                    }
                }
                if let Some(c) = map.remove("const") {
                    map.insert("enum".into(), serde_json::Value::Array(vec![c]));
                }
                // an `enum` without a `type`: the type its values share (utoipa's model wants one)
                if let (Some(serde_json::Value::Array(values)), false) = (map.get("enum"), map.contains_key("type")) {
                    let ty = if values.iter().all(|x| x.is_string()) {
                        Some("string")
                    } else if values.iter().all(|x| x.is_i64() || x.is_u64()) {
                        Some("integer")
                    } else {
                        None
                    };
                    if let Some(ty) = ty {
                        map.insert("type".into(), ty.into());
                    }
                }
                map.values_mut().for_each(|x| rewrite(x, component));
            }
            serde_json::Value::Array(items) => items.iter_mut().for_each(|x| rewrite(x, component)),
            _ => {}
        }
    }
    let mut out = Vec::new();
    for (name, mut def) in defs {
        rewrite(&mut def, &component);
        out.push((component(&name), serde_json::from_value(def).map_err(|e| e.to_string())?));
    }
    rewrite(&mut doc, &component);
    out.push(("Template".to_owned(), serde_json::from_value(doc).map_err(|e| e.to_string())?));
    Ok(out)
}

impl utoipa::PartialSchema for TemplateDocument {
    fn schema() -> RefOr<Schema> {
        // the schema is compiled in and checked by a test: the fallback cannot happen at run time
        template_components()
            .ok()
            .and_then(|parts| parts.into_iter().find(|(n, _)| n == "Template"))
            .map_or_else(|| utoipa::openapi::ObjectBuilder::new().into(), |(_, s)| s)
    }
}

impl ToSchema for TemplateDocument {
    fn name() -> std::borrow::Cow<'static, str> {
        "Template".into()
    }

    fn schemas(schemas: &mut Vec<(String, RefOr<Schema>)>) {
        schemas.extend(template_components().unwrap_or_default().into_iter().filter(|(n, _)| n != "Template"));
    }
}

/// The landmarks document of the scan flow, batch jobs and `grade3d grade
/// --landmarks` (issue #17, item 4): its schema generated from the feature
/// vocabulary, every point and curve ID a property (the IDs as an enum: no
/// other key is accepted), the points every scan must give required.
pub struct LandmarksDocument;

/// A point's coordinates: `[x, y, z]` in the document's `units`.
fn landmark_point_schema() -> serde_json::Value {
    serde_json::json!({"type": "array", "items": {"type": "number"}, "minItems": 3, "maxItems": 3})
}

/// [`LandmarksDocument`]'s schema as JSON.
fn landmarks_schema_json() -> serde_json::Value {
    use grade3d_core::body::vocab::{curve_def, point_def, required_landmarks, CurveId, PointId, VOCABULARY_VERSION};
    let with = |mut schema: serde_json::Value, description: String| {
        if let Some(m) = schema.as_object_mut() {
            m.insert("description".into(), description.into());
        }
        schema
    };
    let points: serde_json::Map<String, serde_json::Value> = PointId::ALL
        .iter()
        .map(|&p| (p.as_str().to_owned(), with(landmark_point_schema(), point_def(p).name.to_owned())))
        .collect();
    let curves: serde_json::Map<String, serde_json::Value> = CurveId::ALL
        .iter()
        .map(|&c| {
            let polyline = serde_json::json!({"type": "array", "items": landmark_point_schema(), "minItems": 2});
            (
                c.as_str().to_owned(),
                with(polyline, format!("{}, as a polyline that replaces the derived one", curve_def(c).name)),
            )
        })
        .collect();
    let required: Vec<&str> = required_landmarks().into_iter().map(PointId::as_str).collect();
    serde_json::json!({
        "type": "object",
        "description": "A body's landmarks: points of the feature vocabulary (`GET /v1/vocabulary`) on the scan, \
            in the scan's frame (Y up, facing +Z).",
        "required": ["vocabulary", "points"],
        "additionalProperties": false,
        "properties": {
            "vocabulary": {
                "type": "integer", "minimum": 1, "maximum": VOCABULARY_VERSION,
                "description": "The vocabulary version the document is written in."
            },
            "units": {"type": "string", "enum": ["m", "cm", "mm"], "description": "Length unit (default m)."},
            "points": {
                "type": "object", "properties": points, "required": required, "additionalProperties": false,
                "description": "Landmarks by point ID."
            },
            "curves": {
                "type": "object", "properties": curves, "additionalProperties": false,
                "description": "Optional curves by curve ID, each replacing the one derived from the points."
            }
        }
    })
}

impl utoipa::PartialSchema for LandmarksDocument {
    fn schema() -> RefOr<Schema> {
        // built from compiled-in tables and checked by a test: the fallback cannot happen at run time
        serde_json::from_value(landmarks_schema_json()).unwrap_or_else(|_| utoipa::openapi::ObjectBuilder::new().into())
    }
}

impl ToSchema for LandmarksDocument {
    fn name() -> std::borrow::Cow<'static, str> {
        "Landmarks".into()
    }
}

/// The feature vocabulary (`GET /v1/vocabulary`, issue #17, item 4): the
/// points and curves a body is described by, which points a landmarks
/// document must give, and which templates place nodes on each point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct Vocabulary {
    /// The version landmarks documents are written in.
    pub version: u32,
    /// The point IDs every landmarks document must give (the curves'
    /// landmarks), in ID order.
    pub landmarks: Vec<String>,
    /// Every point, in ID order.
    pub points: Vec<VocabularyPoint>,
    /// Every curve, in ID order.
    pub curves: Vec<VocabularyCurve>,
}

/// A point of the vocabulary: the crossing of two curves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct VocabularyPoint {
    /// Its ID, as landmarks documents and templates name it.
    pub id: String,
    /// What it is, in ISO 8559-1 terms where the standard names it.
    pub name: String,
    /// Whether a landmarks document must give it.
    pub landmark: bool,
    /// Whether a body may lack it: a point of the arms (vocabulary 3), derived where the arm
    /// landmarks (`upper_arm_*`, `elbow_*`, `wrist_*`) are given, which garments with sleeves need.
    pub optional: bool,
    /// The two curves it lies on.
    pub curves: [String; 2],
    /// The live templates with a node on it.
    pub templates: Vec<String>,
}

/// A curve of the vocabulary.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, ToSchema)]
pub struct VocabularyCurve {
    /// Its ID.
    pub id: String,
    /// What it is.
    pub name: String,
    /// The landmarks it is derived from (none: it follows from other curves).
    pub landmarks: Vec<String>,
    /// Whether a body may lack it (the arms): derived only where all its landmarks are given.
    pub optional: bool,
}

/// Adds the API-key security scheme.
struct ApiKey;

impl Modify for ApiKey {
    fn modify(&self, openapi: &mut utoipa::openapi::OpenApi) {
        let components = openapi.components.get_or_insert_with(Default::default);
        components.add_security_scheme(
            "apiKey",
            SecurityScheme::Http(
                HttpBuilder::new()
                    .scheme(HttpAuthScheme::Bearer)
                    .description(Some(
                        "The API key configured at start (`GRADE3D_API_KEY`); required for template writes, \
                         and for reads with `--protect-reads`.",
                    ))
                    .build(),
            ),
        );
    }
}

/// The document's header and shared components; the paths come from the router.
#[derive(OpenApi)]
#[openapi(
    info(
        title = "grade3d",
        description = "Grades garment feature templates onto bodies (size-chart mannequins or body scans with \
landmarks), refines and flattens them, and returns meshes, sewing patterns (SVG, AAMA DXF, JSON), graded nests, \
grade rules and a fit report. Every error is an RFC 9457 problem document (`application/problem+json`) that names \
the offending field.\n\nGenerated from the code (`grade3d openapi`); do not edit by hand.",
        license(name = "MIT OR Apache-2.0", identifier = "MIT OR Apache-2.0"),
    ),
    servers((url = "http://127.0.0.1:8080")),
    tags(
        (name = "operations", description = "Liveness, readiness, metrics"),
        (name = "templates", description = "The garment template library"),
        (name = "grading", description = "The size-chart and scan flows and their cached results"),
        (name = "jobs", description = "Batch jobs"),
    ),
    components(
        schemas(Problem, Report, LandmarksDocument),
        responses(
            BadRequest, Unauthorized, Forbidden, NotFound, Conflict, TooLarge, UnsupportedMedia,
            Unprocessable, Unavailable, Internal, ArtefactBytes
        ),
    ),
    modifiers(&ApiKey),
)]
pub struct ApiDoc;

/// The OpenAPI document of [`crate::app`]: [`ApiDoc`] with the router's paths.
pub fn openapi() -> utoipa::openapi::OpenApi {
    crate::routes().split_for_parts().1
}

/// [`openapi`] as YAML: what `openapi.yaml` holds, with the types' rustdoc
/// links written as plain code (``[`crate::body::contact`]`` → `` `contact` ``;
/// they occur in descriptions only).
///
/// # Errors
/// Why the document did not serialise (a broken schema; internal).
pub fn openapi_yaml() -> Result<String, String> {
    openapi().to_yaml().map(|y| plain_text(&y)).map_err(|e| e.to_string())
}

/// `text` with each ``[`path::Name`]`` written `` `Name` `` (a type's
/// member kept: ``[`Type::member`]`` → `` `Type::member` ``).
fn plain_text(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(start) = rest.find("[`") {
        let Some(len) = rest[start + 2..].find("`]") else { break };
        let path = &rest[start + 2..start + 2 + len];
        let segments: Vec<&str> = path.split("::").collect();
        // keep from the first segment that names a type (upper case), else the last one
        let from = segments.iter().position(|s| s.starts_with(|c: char| c.is_ascii_uppercase()));
        let kept = segments[from.unwrap_or(segments.len() - 1)..].join("::");
        out.push_str(&rest[..start]);
        out.push('`');
        out.push_str(&kept);
        out.push('`');
        rest = &rest[start + 2 + len + 2..];
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rustdoc_links_become_plain_code() {
        assert_eq!(
            plain_text("a ([`crate::body::contact`]) b [`Collider::settle_fixed`], [`x`] [`super::fabric`]"),
            "a (`contact`) b `Collider::settle_fixed`, `x` `fabric`"
        );
        assert_eq!(plain_text("no link [`unclosed"), "no link [`unclosed");
    }

    /// The template schema in the contract loses nothing of the published
    /// one: re-serialised, it is the published schema with `$defs` hoisted
    /// and `const` as a one-value `enum`.
    #[test]
    fn the_template_schema_keeps_every_constraint() {
        let parts = template_components().unwrap();
        let names: Vec<&str> = parts.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["TemplateBracket", "TemplateVec3", "Template"]);
        let mut want: serde_json::Value = serde_json::from_str(grade3d_core::template::format::SCHEMA_JSON).unwrap();
        let o = want.as_object_mut().unwrap();
        o.remove("$schema");
        o.remove("$id");
        let defs = o.remove("$defs").unwrap();
        let (bracket, vec3) = (defs["bracket"].clone(), defs["vec3"].clone());
        let got = serde_json::to_value(&parts[2].1).unwrap();
        let text = |v: &serde_json::Value| {
            v.to_string()
                .replace(
                    r#""const":"grade3d/garment-template""#,
                    r#""enum":["grade3d/garment-template"],"type":"string""#,
                )
                .replace(r#""enum":[1,-1]"#, r#""enum":[1,-1],"type":"integer""#)
                .replace(r#""enum":["eq1_frame","eq2_offset"]"#, r#""enum":["eq1_frame","eq2_offset"],"type":"string""#)
                .replace("#/$defs/vec3", "#/components/schemas/TemplateVec3")
                .replace("#/$defs/bracket", "#/components/schemas/TemplateBracket")
        };
        assert_eq!(got, serde_json::from_str::<serde_json::Value>(&text(&want)).unwrap());
        assert_eq!(serde_json::to_value(&parts[0].1).unwrap(), bracket);
        assert_eq!(serde_json::to_value(&parts[1].1).unwrap(), vec3);
    }
}
