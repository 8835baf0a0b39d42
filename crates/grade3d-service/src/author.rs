//! `POST /v1/templates/from-garment` (issue #18, item 1): a template
//! authored from a designed garment's file on its design body, stored as a
//! new template. The handler (in `lib.rs`) reads the multipart parts with
//! [`read_author_parts`] and runs [`author`] on the blocking pool; the
//! geometry is [`crate::template::from_garment`].

use std::collections::BTreeMap;

use axum::body::Bytes;
use axum::extract::{FromRequest, Multipart, Request};
use serde::{Deserialize, Serialize};

use super::problem::Problem;
use crate::body::frame::Units;
use crate::io::garment::{read_garment, scaled, GarmentFileError};
use crate::io::gltf::GltfReadOptions;
use crate::template::format::Template;
use crate::template::from_garment::{
    author_from_garment, design_body, detect_units, DesignBody, FromGarmentError, GarmentOptions, Unmapped,
};
use crate::template::library::AuthorError;

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
    /// The design body could not be built (internal).
    #[error(transparent)]
    Body(#[from] AuthorError),
    /// Authoring failed.
    #[error(transparent)]
    Authoring(#[from] FromGarmentError),
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
    let body = design_body(parts.body)?;
    let a = author_from_garment(&parts.name, &pieces, &body, &parts.options)?;
    let report = Authored {
        template: super::store::Entry { name: a.template.name.clone(), version: a.template.version },
        pieces: a.pieces.clone(),
        ease_mm: a.girths.clone(),
        unmapped: a.unmapped.clone(),
        nodes: a.template.nodes.len(),
        faces: a.template.faces.len(),
        units,
    };
    // the template records the body it was designed on: sketch edits apply there (issue #18 item 3)
    let template = Template { design_body: Some(parts.body), ..a.template };
    Ok((template, report))
}
