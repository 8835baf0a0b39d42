//! `POST /v1/templates/from-garment` (issue #18, item 1): a template
//! authored from a designed garment's file on its design body, stored as a
//! new template. The handler (in `lib.rs`) reads the multipart parts with
//! [`read_author_parts`] and runs [`author`] on the blocking pool; the
//! geometry is [`crate::template::from_garment`]. `POST
//! /v1/templates/from-curves` (item 2) runs [`author_curves`]: the panels'
//! Coons patches ([`crate::template::from_curves`]) authored the same way.

use std::collections::BTreeMap;

use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, Request};
use serde::{Deserialize, Serialize};

use super::problem::Problem;
use crate::body::frame::Units;
use crate::io::garment::{read_garment, scaled, GarmentFileError};
use crate::io::gltf::GltfReadOptions;
use crate::template::format::Template;
use crate::template::from_curves::{panels_from_curves, CurvePanel, CurvesOptions, FromCurvesError};
use crate::template::from_garment::{
    author_from_garment, detect_units, DesignBody, FromGarmentError, GarmentOptions, Unmapped,
};

/// Multipart body of `POST /v1/templates/from-garment`.
#[derive(Debug, utoipa::ToSchema)]
pub struct GarmentUpload {
    /// The garment: GLB/glTF with one mesh (or primitive) per pattern piece, named, or OBJ with one
    /// `g`/`o` group per piece; draped on its design body, in that body's frame (+Y up, facing +Z).
    #[schema(value_type = String, format = Binary)]
    pub garment: Vec<u8>,
    /// The new template's name (a slug).
    pub name: String,
    /// The body it was designed on: `reference` (the built-in templates' mannequin, default) or
    /// `makehuman-base` (MakeHuman's base mesh, the body its helper geometry and clothes are modelled on).
    pub body: Option<DesignBody>,
    /// The garment's units: `m`, `cm` or `mm` (default: found from its size).
    pub units: Option<Units>,
    /// Authoring options (JSON): `max_edge_mm` (90), `cut` (`none`, `sides`, `sides_and_centre`),
    /// `profile_points` (7), `nodes` (extra node positions, m), `defaults` (grading defaults), …
    pub options: Option<String>,
}

/// JSON body of `POST /v1/templates/from-curves` (issue #18 item 2).
#[derive(Debug, Clone, Deserialize, utoipa::ToSchema)]
#[serde(deny_unknown_fields)]
pub struct CurvesUpload {
    /// The new template's name (a slug).
    pub name: String,
    /// The body the curves were drawn on (as for `from-garment`; default `reference`), in its
    /// frame: metres, +Y up, facing +Z.
    #[serde(default)]
    pub body: DesignBody,
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
    /// The pieces after cutting (a tube is cut into front and back).
    pub pieces: Vec<String>,
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

/// The parts of an authoring request.
#[derive(Debug, Clone)]
pub struct AuthorParts {
    /// The garment file.
    pub garment: Bytes,
    /// The template's name.
    pub name: String,
    /// The design body.
    pub body: DesignBody,
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
    /// The design body could not be built (internal: the embedded model).
    #[error("{0}")]
    Body(String),
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

/// Reads the parts `garment`, `name` and optionally `body`, `units` and
/// `options` of a body already within the limit `max`.
///
/// # Errors
/// [`Problem`] (400) naming the part: a malformed multipart body, an unknown
/// or missing part, text that is not UTF-8, a value not allowed, options
/// that are not the options' JSON.
pub async fn read_author_parts(req: Request, max: usize) -> Result<AuthorParts, Problem> {
    let mut mp = Multipart::from_request(req, &())
        .await
        .map_err(|e| Problem::bad_request("invalid-multipart", e.body_text()).field("body"))?;
    let (mut garment, mut name, mut body, mut units, mut options) = (None, None, DesignBody::default(), None, None);
    while let Some((part, data)) = super::next_part(&mut mp, max).await? {
        match part.as_str() {
            "garment" => garment = Some(data),
            "name" => name = Some(text(&part, &data)?),
            "body" => body = value(&part, &data, "reference, makehuman-base")?,
            "units" => units = Some(value(&part, &data, "m, cm, mm")?),
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
    Ok(AuthorParts { garment, name, body, units, options: options.unwrap_or_default() })
}

/// Authors the template (not yet stored): the garment read, scaled to
/// metres, authored on its design body.
///
/// # Errors
/// [`AuthorRequestError`].
pub fn author(parts: &AuthorParts) -> Result<(Template, Authored), AuthorRequestError> {
    let pieces = read_garment(&parts.garment, &GltfReadOptions::default())?;
    let units = match parts.units {
        Some(u) => u,
        None => detect_units(&pieces).ok_or(AuthorRequestError::Units)?,
    };
    let pieces = scaled(pieces, units.metres());
    // the process's copy of the design body (built once, shared with sketch edits)
    let body = super::edit::design_body(parts.body).map_err(AuthorRequestError::Body)?;
    let a = author_from_garment(&parts.name, &pieces, body, &parts.options)?;
    Ok(stored(a, parts.body, units))
}

/// The template as stored (it records the body it was designed on: sketch
/// edits apply there, issue #18 item 3) and the answer's report.
fn stored(a: crate::template::from_garment::Authored, body: DesignBody, units: Units) -> (Template, Authored) {
    let report = Authored {
        template: super::store::Entry { name: a.template.name.clone(), version: a.template.version },
        pieces: a.pieces,
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
/// [`AuthorRequestError`].
pub fn author_curves(input: &CurvesUpload) -> Result<(Template, Authored), AuthorRequestError> {
    let pieces = panels_from_curves(&input.panels, &input.curves)?;
    let body = super::edit::design_body(input.body).map_err(AuthorRequestError::Body)?;
    let a = author_from_garment(&input.name, &pieces, body, &input.options)?;
    Ok(stored(a, input.body, Units::Metres))
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
