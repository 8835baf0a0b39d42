//! `POST /v1/templates/from-garment` (issue #18, item 1): a template
//! authored from a designed garment's file on its design body, stored as a
//! new template. The handler (in `lib.rs`) reads the multipart parts with
//! [`read_author_parts`] and runs [`author`] on the blocking pool; the
//! geometry is [`crate::template::from_garment`]. `POST
//! /v1/templates/from-curves` (item 2) runs [`author_curves`]: the panels'
//! Coons patches ([`crate::template::from_curves`]) authored the same way.
//!
//! The design body is one of ours (`body`), a size of a chart
//! (`body_chart` and `body_size`: the mannequin fitted to that row), or
//! the avatar the garment was draped on (`body_scan`, with or without
//! `body_landmarks`; read as any scan is, issue #11): the garment is then
//! in the avatar's own axes and units and follows it into the body frame,
//! and the scan is kept in the store under its content id
//! ([`crate::store::TemplateStore::put_scan`], written before the template
//! that names it) so that the template's sketch edits are made on it.

use std::collections::BTreeMap;
use std::sync::Arc;

use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, Request};
use serde::{Deserialize, Serialize};

use super::problem::Problem;
use crate::body::feature::FeatureBody;
use crate::body::frame::{FrameHints, FrameReport, Units};
use crate::io::garment::{read_garment, scaled, GarmentFileError};
use crate::io::gltf::GltfReadOptions;
use crate::mannequin::size_chart::{parse_json, SizeChart, SizeChartOptions};
use crate::store::StoredScan;
use crate::template::format::Template;
use crate::template::from_curves::{panels_from_curves, CurvePanel, CurvesOptions, FromCurvesError};
use crate::template::from_garment::{
    author_from_garment, detect_units, DesignBody, FromGarmentError, GarmentOptions, GrainFound, Unmapped,
};
use crate::template::garment_panels::PanelMesh;
use crate::AppState;

/// Multipart body of `POST /v1/templates/from-garment`.
#[derive(Debug, utoipa::ToSchema)]
pub struct GarmentUpload {
    /// The garment: GLB/glTF with one mesh (or primitive) per pattern piece, named, or OBJ with one
    /// `g`/`o` group per piece; draped on its design body, in that body's frame (+Y up, facing +Z), or,
    /// with `body_scan`, in the scan's own axes and units.
    #[schema(value_type = String, format = Binary)]
    pub garment: Vec<u8>,
    /// The new template's name (a slug).
    pub name: String,
    /// The body it was designed on: `reference` (the built-in templates' mannequin, default) or
    /// `makehuman-base` (MakeHuman's base mesh, the body its helper geometry and clothes are modelled on).
    /// At most one of `body`, `body_scan` and `body_chart`.
    pub body: Option<String>,
    /// The avatar the garment was draped on (GLB, as a scan: any units, +Y or +Z up, any facing, with or
    /// without landmarks), kept with the template as its design body.
    #[schema(value_type = Option<String>, format = Binary)]
    pub body_scan: Option<Vec<u8>>,
    /// The avatar's landmarks (JSON, as for a scan), all, some or none.
    pub body_landmarks: Option<String>,
    /// The avatar's up axis (`+y`, `+z`; default: found).
    pub up: Option<String>,
    /// The avatar's facing (`+x` … `-z`; default: found).
    pub facing: Option<String>,
    /// A size chart (CSV text or a JSON size chart document) one of whose sizes the garment was designed
    /// on: the mannequin fitted to that size.
    pub body_chart: Option<String>,
    /// The size of `body_chart` (its label).
    pub body_size: Option<String>,
    /// The garment's units: `m`, `cm` or `mm` (default: found from its size); with `body_scan`, the
    /// avatar's and the garment's.
    pub units: Option<Units>,
    /// Authoring options (JSON): `max_edge_mm` (90), `cut` (`none`, `sides`, `sides_and_centre`),
    /// `profile_points` (7), `nodes` (extra node positions, m), `defaults` (grading defaults),
    /// `grain_from_uv` (true: a piece's grain along its texture coordinates' `v`, the pattern layout
    /// CLO3D, Browzwear and Marvelous Designer export; false for a texture atlas), …
    pub options: Option<String>,
}

/// JSON body of `POST /v1/templates/from-curves` (issue #18 item 2).
#[derive(Debug, Clone, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CurvesUpload {
    /// The new template's name (a slug).
    pub name: String,
    /// The body the curves were drawn on (default `reference`), in its frame: metres, +Y up, facing +Z:
    /// `reference`, `makehuman-base`, `{"chart-size": {"sex", "row"}}` as a template records it, or
    /// `{"scan": {"id"}}`, a design scan the store keeps (a template authored on it names it).
    #[serde(default)]
    pub body: Option<DesignBody>,
    /// A size chart (CSV text or a JSON size chart document) whose size `body_size` the curves were
    /// drawn on (instead of `body`).
    #[serde(default)]
    #[schema(value_type = Option<crate::api::SizeChartInput>)]
    pub body_chart: Option<serde_json::Value>,
    /// The size of `body_chart` (its label).
    #[serde(default)]
    pub body_size: Option<String>,
    /// The panels, each as its four boundary curves in metres (bottom and top from the left curve to
    /// the right one, left and right from the bottom up; a side may be one point); panels meet along
    /// shared curves, which become their seams.
    pub panels: Vec<CurvePanel>,
    /// The patches' options (JSON): `samples` (24 intervals a side), `coons` (`blend`: `hermite` or
    /// `linear`; `corner_tolerance_mm`, 0.01).
    #[serde(default)]
    #[schema(value_type = Object)]
    pub curves: CurvesOptions,
    /// Authoring options, as for `from-garment`.
    #[serde(default)]
    #[schema(value_type = Object)]
    pub options: GarmentOptions,
}

/// What authoring made (201 Created).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Authored {
    /// The stored template's name and version.
    pub template: super::store::Entry,
    /// The body it was designed on, as the template records it.
    pub design_body: DesignBody,
    /// The pieces after cutting (a tube is cut into front and back).
    pub pieces: Vec<String>,
    /// Each piece's grain: from its texture coordinates (the pattern layout, the grain along `v`) or the
    /// body's vertical, and how far the template's grain line (a pair of nodes) runs from it.
    pub grains: BTreeMap<String, GrainFound>,
    /// The girths the garment goes around and its ease there, mm (the template's `ease_mm`).
    pub ease_mm: BTreeMap<String, f64>,
    /// What could not be mapped (a piece far from every feature point, a girth line a seam crosses
    /// away from its feature points, …): the template is stored regardless.
    pub unmapped: Vec<Unmapped>,
    /// Template nodes.
    pub nodes: usize,
    /// Template faces.
    pub faces: usize,
    /// The garment's units as read (stated or found).
    pub units: Units,
}

/// Where an authoring request's design body comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum PartsBody {
    /// Named, a chart's size, or a stored scan ([`super::edit::design_body`]).
    Design(DesignBody),
    /// An avatar uploaded with the garment (kept as it was uploaded).
    Scan(StoredScan),
}

/// The parts of an authoring request.
#[derive(Debug, Clone)]
pub struct AuthorParts {
    /// The garment file.
    pub garment: Bytes,
    /// The template's name.
    pub name: String,
    /// The design body.
    pub body: PartsBody,
    /// The stated units.
    pub units: Option<Units>,
    /// The options.
    pub options: GarmentOptions,
}

/// Why an authoring request failed.
#[derive(Debug, thiserror::Error)]
pub enum AuthorRequestError {
    /// The garment file is unreadable.
    #[error(transparent)]
    File(#[from] GarmentFileError),
    /// No unit makes the garment garment-sized.
    #[error("the garment's size fits no unit (m, cm, mm): state `units`")]
    Units,
    /// Authoring failed.
    #[error(transparent)]
    Authoring(#[from] FromGarmentError),
    /// The curves make no panel.
    #[error(transparent)]
    Curves(#[from] FromCurvesError),
}

fn text(name: &str, data: &[u8]) -> Result<String, Problem> {
    String::from_utf8(data.to_vec())
        .map(|s| s.trim().to_owned())
        .map_err(|_| Problem::bad_request("not-utf8", format!("part `{name}` is not UTF-8")).field(name))
}

/// A text part naming one of an enum's values (its JSON name).
fn value<T: serde::de::DeserializeOwned>(part: &str, data: &[u8], allowed: &str) -> Result<T, Problem> {
    let t = text(part, data)?;
    serde_json::from_value(serde_json::Value::String(t.clone())).map_err(|_| {
        Problem::bad_request("invalid-part", format!("part `{part}` is `{t}`; allowed: {allowed}")).field(part)
    })
}

/// The size `size` of a chart (CSV text or a JSON document) as a design
/// body, every refusal naming `chart_field` or `size_field`.
///
/// # Errors
/// [`Problem`] (400): the chart's ([`super::errors::chart_problem`]), a
/// size the chart does not have (naming those it has).
pub fn chart_size(
    chart: &serde_json::Value,
    size: &str,
    opts: &SizeChartOptions,
    (chart_field, size_field): (&str, &str),
) -> Result<DesignBody, Problem> {
    // a multipart part or a file is text: JSON where it opens as an object, else CSV
    let parsed: SizeChart = match chart {
        serde_json::Value::String(text) if text.trim_start().starts_with('{') => {
            parse_json(text, opts).map_err(|e| super::errors::chart_problem(&e))
        }
        other => super::parse_chart_with(*opts, other, None),
    }
    .map_err(|p| p.field(chart_field))?;
    let row = parsed.rows.iter().find(|r| r.size == size).ok_or_else(|| {
        let sizes: Vec<&str> = parsed.rows.iter().map(|r| r.size.as_str()).collect();
        Problem::bad_request("unknown-size", format!("the chart has no size `{size}`; it has: {}", sizes.join(", ")))
            .field(size_field)
    })?;
    Ok(DesignBody::ChartSize { sex: parsed.sex, row: row.clone() })
}

/// Reads the parts `garment`, `name` and optionally `body`, `body_scan`
/// (with `body_landmarks`, `up`, `facing`), `body_chart` (with
/// `body_size`), `units` and `options` of a body already within the limit
/// `max`.
///
/// # Errors
/// [`Problem`] (400) naming the part: a malformed multipart body, an unknown
/// or missing part, text that is not UTF-8, a value not allowed, options
/// that are not the options' JSON, more than one design body, a chart or
/// size without the other, a chart the library refuses or that lacks the size.
pub async fn read_author_parts(req: Request, max: usize, charts: SizeChartOptions) -> Result<AuthorParts, Problem> {
    let mut mp = Multipart::from_request(req, &())
        .await
        .map_err(|e| Problem::bad_request("invalid-multipart", e.body_text()).field("body"))?;
    let (mut garment, mut name, mut body, mut units, mut options) = (None, None, None, None, None);
    let (mut scan, mut landmarks, mut chart, mut size) = (None, None, None, None);
    let mut hints = FrameHints::default();
    while let Some((part, data)) = super::next_part(&mut mp, max).await? {
        match part.as_str() {
            "garment" => garment = Some(data),
            "name" => name = Some(text(&part, &data)?),
            "body" => body = Some(value::<DesignBody>(&part, &data, "reference, makehuman-base")?),
            "body_scan" => scan = Some(data),
            "body_landmarks" => landmarks = Some(text(&part, &data)?),
            "body_chart" => chart = Some(text(&part, &data)?),
            "body_size" => size = Some(text(&part, &data)?),
            "units" => units = Some(value(&part, &data, "m, cm, mm")?),
            "up" => hints.up = Some(value(&part, &data, "+y, +z")?),
            "facing" => hints.facing = Some(value(&part, &data, "+x, -x, +y, -y, +z, -z")?),
            "options" => {
                let t = text(&part, &data)?;
                options = Some(serde_json::from_str::<GarmentOptions>(&t).map_err(|e| {
                    Problem::bad_request("invalid-options", format!("part `options`: {e}")).field("options")
                })?);
            }
            other => return Err(Problem::bad_request("unknown-part", format!("unknown part `{other}`")).field(other)),
        }
    }
    let garment = garment.ok_or_else(|| {
        Problem::bad_request("missing-part", "the `garment` part (GLB or OBJ) is missing").field("garment")
    })?;
    let name = name.ok_or_else(|| Problem::bad_request("missing-part", "the `name` part is missing").field("name"))?;
    let given: Vec<&str> = [("body", body.is_some()), ("body_scan", scan.is_some()), ("body_chart", chart.is_some())]
        .into_iter()
        .filter_map(|(n, g)| g.then_some(n))
        .collect();
    if given.len() > 1 {
        return Err(Problem::bad_request(
            "conflicting-parts",
            format!("one design body, not {}: `{}`", given.len(), given.join("`, `")),
        )
        .field(given[1]));
    }
    let lone = |part: &str, needs: &str| {
        Problem::bad_request("missing-part", format!("`{part}` comes with `{needs}`")).field(needs)
    };
    if landmarks.is_some() && scan.is_none() {
        return Err(lone("body_landmarks", "body_scan"));
    }
    if (hints.up.is_some() || hints.facing.is_some()) && scan.is_none() {
        return Err(lone(if hints.up.is_some() { "up" } else { "facing" }, "body_scan"));
    }
    let body = match (scan, chart, size) {
        (Some(glb), _, _) => {
            hints.units = units;
            PartsBody::Scan(StoredScan { glb: glb.to_vec(), landmarks, hints })
        }
        (None, Some(c), Some(sz)) => {
            PartsBody::Design(chart_size(&serde_json::Value::String(c), &sz, &charts, ("body_chart", "body_size"))?)
        }
        (None, Some(_), None) => return Err(lone("body_chart", "body_size")),
        (None, None, Some(_)) => return Err(lone("body_size", "body_chart")),
        (None, None, None) => PartsBody::Design(body.unwrap_or_default()),
    };
    Ok(AuthorParts { garment, name, body, units, options: options.unwrap_or_default() })
}

/// Authors the template (not yet stored): the garment read, brought into
/// the body frame (scaled to metres; with an avatar, as the avatar is),
/// authored on its design body. An uploaded avatar is kept in the store
/// first (module docs).
///
/// # Errors
/// [`Problem`]: the garment's, the design body's, the authoring's.
pub fn author(s: &AppState, parts: &AuthorParts) -> Result<(Template, Authored), Problem> {
    match &parts.body {
        PartsBody::Design(which) => {
            let body = super::edit::design_body(s, which)?;
            Ok(author_on(parts, &body, which.clone(), None)?)
        }
        PartsBody::Scan(scan) => {
            let read = super::edit::read_design_scan(s, scan)?;
            let id = scan.content_id()?;
            let frame = read.scan.frame;
            let authored = author_on(parts, &read.body, DesignBody::Scan { id: id.clone() }, Some(frame))?;
            s.0.store.put_scan(&id, scan)?;
            s.0.design_bodies.keep(format!("scan:{id}"), Arc::new(read.body));
            Ok(authored)
        }
    }
}

/// [`author`] on a design body already built, recorded as `which`: the
/// garment in the body frame (`scan` `None`: in metres or the stated or
/// found units), or in the scan's own axes and units, which the scan's
/// frame ([`FrameReport::transform`]) brings into it. What `grade3d
/// author` runs.
///
/// # Errors
/// [`AuthorRequestError`]: the garment's, its units', the authoring's.
pub fn author_on(
    parts: &AuthorParts,
    body: &FeatureBody,
    which: DesignBody,
    scan: Option<FrameReport>,
) -> Result<(Template, Authored), AuthorRequestError> {
    let pieces = read_garment(&parts.garment, &GltfReadOptions::default())?;
    let (pieces, units) = match scan {
        Some(frame) => {
            let to_body = frame.transform();
            let pieces = pieces
                .into_iter()
                .map(|p| PanelMesh { positions: p.positions.iter().map(|&q| to_body.apply(q)).collect(), ..p })
                .collect();
            (pieces, frame.units)
        }
        None => {
            let units = match parts.units {
                Some(u) => u,
                None => detect_units(&pieces).ok_or(AuthorRequestError::Units)?,
            };
            (scaled(pieces, units.metres()), units)
        }
    };
    let a = author_from_garment(&parts.name, &pieces, body, &parts.options)?;
    Ok(stored(a, which, units))
}

/// The template as stored (it records the body it was designed on: sketch
/// edits apply there, issue #18 item 3) and the answer's report.
fn stored(a: crate::template::from_garment::Authored, body: DesignBody, units: Units) -> (Template, Authored) {
    let report = Authored {
        template: super::store::Entry { name: a.template.name.clone(), version: a.template.version },
        design_body: body.clone(),
        pieces: a.pieces,
        grains: a.grains,
        ease_mm: a.girths,
        unmapped: a.unmapped,
        nodes: a.template.nodes.len(),
        faces: a.template.faces.len(),
        units,
    };
    (Template { design_body: Some(body), ..a.template }, report)
}

/// A template from curves (issue #18 item 2): the panels' Coons patches
/// ([`panels_from_curves`]) authored as a designed garment on their body;
/// what `POST /v1/templates/from-curves` runs.
///
/// # Errors
/// [`Problem`]: the design body's (one of `body` and `body_chart`, the
/// chart with its size), the curves', the authoring's.
pub fn author_curves(
    s: &AppState,
    input: &CurvesUpload,
    charts: &SizeChartOptions,
) -> Result<(Template, Authored), Problem> {
    let which = match (&input.body, &input.body_chart, &input.body_size) {
        (Some(_), Some(_), _) => {
            return Err(Problem::bad_request("conflicting-parts", "one design body: `body` or `body_chart`, not both")
                .field("body_chart"))
        }
        (_, Some(chart), Some(size)) => chart_size(chart, size, charts, ("body_chart", "body_size"))?,
        (_, Some(_), None) => {
            return Err(Problem::bad_request("missing-part", "`body_chart` comes with `body_size`").field("body_size"))
        }
        (_, None, Some(_)) => {
            return Err(Problem::bad_request("missing-part", "`body_size` comes with `body_chart`").field("body_chart"))
        }
        (body, None, None) => body.clone().unwrap_or_default(),
    };
    let pieces = panels_from_curves(&input.panels, &input.curves).map_err(AuthorRequestError::from)?;
    let body = super::edit::design_body(s, &which)?;
    let a = author_from_garment(&input.name, &pieces, &body, &input.options).map_err(AuthorRequestError::from)?;
    Ok(stored(a, which, Units::Metres))
}

#[cfg(test)]
mod tests {
    use axum::body::Body;
    use axum::http::{header, Request, StatusCode};
    use http_body_util::BodyExt;
    use serde_json::{json, Value};
    use tower::ServiceExt;

    use crate::body::vocab::CurveId;
    use crate::template::library::reference_body;

    async fn post(s: &crate::AppState, body: &Value, key: bool) -> (StatusCode, Option<String>, Value) {
        let mut req = Request::post("/v1/templates/from-curves").header(header::CONTENT_TYPE, "application/json");
        if key {
            req = req.header(header::AUTHORIZATION, "Bearer k");
        }
        let resp = crate::app(s.clone()).oneshot(req.body(Body::from(body.to_string())).unwrap()).await.unwrap();
        let status = resp.status();
        let location = resp.headers().get(header::LOCATION).map(|v| v.to_str().unwrap().to_owned());
        let bytes = resp.into_body().collect().await.unwrap().to_bytes();
        (status, location, serde_json::from_slice(&bytes).unwrap_or(Value::Null))
    }

    /// A skirt on the reference body as four panels: front and back, waist
    /// to hip and hip to a hem 300 mm below the hip, each ring an ellipse
    /// round the body's girth (30 mm out; the hem 60 mm).
    fn skirt_panels() -> Value {
        let body = reference_body().unwrap();
        let ring = |c: CurveId, out: f64, drop: f64| {
            let l = &body.curves[&c].polyline;
            let m = l.centroid();
            let rx = l.points.iter().map(|p| (p.x - m.x).abs()).fold(0.0, f64::max) + out;
            let rz = l.points.iter().map(|p| (p.z - m.z).abs()).fold(0.0, f64::max) + out;
            move |a: f64| [m.x + rx * a.cos(), m.y - drop, m.z + rz * a.sin()]
        };
        let rings = [ring(CurveId::Waist, 0.03, 0.0), ring(CurveId::Hip, 0.03, 0.0), ring(CurveId::Hip, 0.06, 0.3)];
        let arc = |r: usize, a0: f64| -> Vec<[f64; 3]> {
            (0..=40).map(|k| rings[r](a0 + std::f64::consts::PI * k as f64 / 40.0)).collect()
        };
        let mut panels = Vec::new();
        for (band, top) in [("upper", 0), ("lower", 1)] {
            for (piece, a0) in [("front", 0.0), ("back", std::f64::consts::PI)] {
                let side = |a: f64| vec![rings[top + 1](a), rings[top](a)];
                panels.push(json!({
                    "name": format!("{piece}-{band}"),
                    "bottom": arc(top + 1, a0), "top": arc(top, a0),
                    "left": side(a0), "right": side(a0 + std::f64::consts::PI),
                }));
            }
        }
        Value::Array(panels)
    }

    #[tokio::test]
    async fn a_template_is_authored_from_curves_and_every_refusal_names_its_field() {
        let (s, dir) = crate::tests::state();
        let panels = skirt_panels();
        let ok = json!({"name": "curve-skirt", "panels": panels});
        assert_eq!(post(&s, &ok, false).await.0, StatusCode::UNAUTHORIZED);
        let (status, location, answer) = post(&s, &ok, true).await;
        assert_eq!(status, StatusCode::CREATED, "{answer}");
        assert_eq!(location.as_deref(), Some("/v1/templates/curve-skirt"));
        assert_eq!(answer["template"], json!({"name": "curve-skirt", "version": 1}));
        assert_eq!(answer["pieces"].as_array().unwrap().len(), 4, "{answer}");
        assert!(answer["ease_mm"]["hip"].as_f64().unwrap() > 0.0, "{answer}");
        // stored, with its design body
        let (_, t) = s.0.store.get("curve-skirt", None).unwrap();
        assert_eq!(t.design_body, Some(crate::template::from_garment::DesignBody::Reference));
        assert_eq!(post(&s, &ok, true).await.0, StatusCode::CONFLICT);
        // refusals
        let mut broken = panels.clone();
        broken[2]["left"][0][0] = json!(9.0);
        let cases = [
            (json!({"name": "a", "panels": []}), StatusCode::UNPROCESSABLE_ENTITY, "panels", "no panel"),
            (json!({"name": "a", "panels": broken}), StatusCode::UNPROCESSABLE_ENTITY, "panels", "front-lower"),
            (
                json!({"name": "a", "panels": panels, "curves": {"samples": 0}}),
                StatusCode::BAD_REQUEST,
                "curves.samples",
                "samples",
            ),
            (json!({"name": "a", "panels": panels, "colour": 1}), StatusCode::BAD_REQUEST, "body", "colour"),
            (json!({"name": "a b", "panels": panels}), StatusCode::BAD_REQUEST, "name", "name"),
        ];
        for (body, status, field, names) in cases {
            let (got, _, problem) = post(&s, &body, true).await;
            assert_eq!(got, status, "{problem}");
            assert!(problem["field"].as_str().unwrap_or_default().starts_with(field), "{problem}");
            assert!(problem["detail"].as_str().unwrap().contains(names), "{problem}");
        }
        let _ = std::fs::remove_dir_all(dir);
    }
}
