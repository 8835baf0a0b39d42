//! `POST /v1/templates/{name}/edits` (issue #18 items 3–4): one sketch edit
//! (seed 000 §4) applied to the live version of a template on its design
//! body and stored as the next version, the previous ones kept (undo is a
//! `PUT` of an earlier version, read with `GET /v1/templates/{name}?version=N`).
//!
//! The geometry and the constraints of seed 002 are the core's
//! [`crate::template::edit::apply_edit`]; this module runs it on the live
//! version ([`edit`], on the bounded pool, called by the handler in
//! `lib.rs`), stores the result only if no other write came first
//! ([`crate::store::TemplateStore::put_edit`]: 409 otherwise), and keeps
//! the preview — the coarse garment (decoded nodes and faces) and the
//! refined garment on the design body, GLB — in the result cache as a
//! grade's artefacts are kept, under the content address of the stored
//! document: `GET /v1/results/{id}/{artefact}` serves them.
//!
//! Failure modes: the template's (404), the edit's (every refusal a
//! problem naming the node, edge, panel, girth or constraint, mapped in
//! `errors.rs`), a write that lost the race (409).

use std::collections::BTreeMap;
use std::sync::{Arc, OnceLock};

use serde::{Deserialize, Serialize};

use crate::api::ArtefactLink;
use crate::body::feature::FeatureBody;
use crate::geom::mesh::TriMesh;
use crate::io::gltf::write_glb;
use crate::problem::Problem;
use crate::results::{content_id, Stored};
use crate::store::{Entry, StoredScan};
use crate::template::edit::{apply_edit, EditOptions, Resolution, SketchEdit};
use crate::template::from_garment::DesignBody;
use crate::work::Artefact;
use crate::AppState;

/// Most chart-size and scan design bodies kept in memory (count): the
/// last ones resolved; the built-in bodies are kept for the process.
const KEPT_DESIGN_BODIES: usize = 4;

/// The design bodies resolved from charts and stored scans, the newest
/// last (at most [`KEPT_DESIGN_BODIES`]).
#[derive(Debug, Default)]
pub struct DesignBodies(std::sync::Mutex<Vec<(String, Arc<FeatureBody>)>>);

impl DesignBodies {
    fn get(&self, key: &str) -> Option<Arc<FeatureBody>> {
        let kept = self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        kept.iter().find(|(k, _)| k == key).map(|(_, b)| b.clone())
    }

    /// Keeps `body` under `key`, dropping the oldest beyond the bound.
    pub fn keep(&self, key: String, body: Arc<FeatureBody>) {
        let mut kept = self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        kept.retain(|(k, _)| *k != key);
        kept.push((key, body));
        let excess = kept.len().saturating_sub(KEPT_DESIGN_BODIES);
        kept.drain(..excess);
    }
}

/// The built-in design bodies' feature models, built once per process.
///
/// # Errors
/// The build's error, as text (the embedded model: never a request's error).
fn builtin_body(which: &DesignBody) -> Result<Arc<FeatureBody>, String> {
    static REFERENCE: OnceLock<Result<Arc<FeatureBody>, String>> = OnceLock::new();
    static MAKEHUMAN_BASE: OnceLock<Result<Arc<FeatureBody>, String>> = OnceLock::new();
    let cell = match which {
        DesignBody::MakehumanBase => &MAKEHUMAN_BASE,
        _ => &REFERENCE,
    };
    cell.get_or_init(|| crate::template::from_garment::design_body(which).map(Arc::new).map_err(|e| e.to_string()))
        .clone()
        .map_err(|e| format!("the design body {which:?}: {e}"))
}

/// The feature model of the reference body (built once per process).
///
/// # Errors
/// The build's error, as text.
pub fn reference_body() -> Result<Arc<FeatureBody>, String> {
    builtin_body(&DesignBody::Reference)
}

/// `p` naming `to` where it named `from`: a scan or chart read for a design
/// body is refused by the field of the request that gave it.
fn renamed(mut p: Problem, renames: &[(&str, &str)]) -> Problem {
    if let Some(f) = p.field.as_mut() {
        if let Some((_, to)) = renames.iter().find(|(from, _)| f == from) {
            *f = (*to).to_owned();
        }
    }
    p
}

/// A scan made into a design body: read as any scan is
/// ([`crate::work::read_body`]), its problems naming the request's
/// `body_scan` and `body_landmarks`.
///
/// # Errors
/// [`Problem`]: the scan's and its landmarks' (4xx), the embedded model's (500).
pub fn read_design_scan(s: &AppState, scan: &StoredScan) -> Result<crate::work::ReadBody, Problem> {
    let opts = crate::work::WorkOptions { max_scan_vertices: s.0.cfg.max_scan_vertices, ..Default::default() };
    let input = crate::work::BodyInput {
        name: "body_scan",
        glb: &scan.glb,
        landmarks: scan.landmarks.as_deref(),
        hints: scan.hints,
    };
    crate::work::read_body(&input, &opts)
        .map_err(|e| renamed(Problem::from(e), &[("scan", "body_scan"), ("landmarks", "body_landmarks")]))
}

/// The feature model of a design body: a built-in one built once per
/// process; a chart size fitted, a stored scan read from the store — each
/// kept among the last [`KEPT_DESIGN_BODIES`].
///
/// # Errors
/// [`Problem`]: a chart size whose mannequin cannot be fitted (422, field
/// `body_chart`); a scan the store does not hold (422, `body`) or that
/// cannot be read (the scan's problems, `body_scan`); the store's or the
/// embedded model's failure (500).
pub fn design_body(s: &AppState, which: &DesignBody) -> Result<Arc<FeatureBody>, Problem> {
    let internal = |e: &dyn std::fmt::Display| {
        tracing::error!(error = %e, "design body");
        Problem::internal()
    };
    let key = match which {
        DesignBody::Reference | DesignBody::MakehumanBase => return builtin_body(which).map_err(|e| internal(&e)),
        DesignBody::Scan { id } => format!("scan:{id}"),
        DesignBody::ChartSize { .. } => {
            content_id(&[b"chart-size", serde_json::to_string(which).map_err(|e| internal(&e))?.as_bytes()])
        }
    };
    if let Some(body) = s.0.design_bodies.get(&key) {
        return Ok(body);
    }
    let body = match which {
        DesignBody::Scan { id } => {
            let scan = s.0.store.get_scan(id)?.ok_or_else(|| {
                Problem::unprocessable("design-body-unknown-scan", format!("no stored design scan `{id}`"))
                    .field("body")
            })?;
            read_design_scan(s, &scan)?.body
        }
        // a chart's size: the core's fit; a size that cannot be fitted is the request's fault
        _ => crate::template::from_garment::design_body(which).map_err(|e| match (e, which) {
            (crate::template::library::AuthorError::Fit(source), DesignBody::ChartSize { row, .. }) => renamed(
                Problem::from(crate::work::WorkError::Fit { size: row.size.clone(), source }),
                &[("chart", "body_chart")],
            ),
            (e, _) => internal(&e),
        })?,
    };
    let body = Arc::new(body);
    s.0.design_bodies.keep(key, body.clone());
    Ok(body)
}

/// What an edit did (the report of its preview's result, too).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct EditReport {
    /// The new version: the template's name and the version it is stored as.
    pub template: Entry,
    /// The version the edit was applied to.
    pub based_on: u32,
    /// The body the edit was made on.
    pub design_body: DesignBody,
    /// Nodes moved (mirrored counterparts included), ascending.
    pub moved_nodes: Vec<u32>,
    /// Edges given new profiles (mirrored counterparts included), ascending.
    pub edited_edges: Vec<u32>,
    /// Constraints the edit kept by changing it (a mirrored edit, a centre
    /// node kept on the symmetry plane) and placement rules it released.
    pub resolved: Vec<Resolution>,
    /// Each declared girth's ease on the design body after the edit, mm.
    pub ease_mm: BTreeMap<String, f64>,
}

/// The preview's downloads.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct Preview {
    /// The preview's result (`GET /v1/results/{id}`).
    pub href: String,
    /// `{name}-v{version}.coarse.glb` (the decoded nodes and faces) and
    /// `{name}-v{version}.refined.glb` (the template's subdivision levels,
    /// no collision), on the design body, metres.
    pub artefacts: Vec<ArtefactLink>,
}

/// The answer of `POST /v1/templates/{name}/edits`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, utoipa::ToSchema)]
pub struct TemplateEdited {
    /// What the edit did.
    pub report: EditReport,
    /// The new version's document, as `GET /v1/templates/{name}?version=N` answers it.
    #[schema(value_type = crate::api::TemplateDocument)]
    pub document: serde_json::Value,
    /// The coarse and refined garment on the design body.
    pub preview: Preview,
}

fn glb(mesh: &TriMesh) -> Result<Vec<u8>, Problem> {
    write_glb(mesh, None, &[], "grade3d").map_err(|e| {
        tracing::error!(error = %e, "preview GLB");
        Problem::internal()
    })
}

/// Applies `request` to the live version of `name` and stores the result
/// (module docs). Blocking: run it on the pool.
///
/// # Errors
/// [`Problem`]: the store's, the edit's (422 naming what breaks), a preview
/// that cannot be written (500).
pub fn edit(s: &AppState, name: &str, request: &SketchEdit) -> Result<TemplateEdited, Problem> {
    let (based_on, t) = s.0.store.get(name, None)?;
    let which = t.design_body.clone().unwrap_or_default();
    let body = design_body(s, &which)?;
    let edited = apply_edit(&t, &body, request, &EditOptions::default())?;
    let template = s.0.store.put_edit(&edited.template, based_on)?;
    let (_, json) = s.0.store.get_json(name, Some(template.version))?;
    let document: serde_json::Value = serde_json::from_str(&json).map_err(|e| {
        tracing::error!(error = %e, "stored template JSON");
        Problem::internal()
    })?;
    let id = content_id(&[b"sketch-edit", json.as_bytes()]);
    let stem = format!("{name}-v{}", template.version);
    let artefacts = vec![
        Artefact { name: format!("{stem}.coarse.glb"), media_type: "model/gltf-binary", bytes: glb(&edited.coarse)? },
        Artefact { name: format!("{stem}.refined.glb"), media_type: "model/gltf-binary", bytes: glb(&edited.refined)? },
    ];
    let report = EditReport {
        template,
        based_on,
        design_body: which.clone(),
        moved_nodes: edited.moved_nodes,
        edited_edges: edited.edited_edges,
        resolved: edited.resolved,
        ease_mm: edited.ease_mm,
    };
    let report_json = serde_json::to_value(&report).map_err(|e| {
        tracing::error!(error = %e, "edit report");
        Problem::internal()
    })?;
    let summary = crate::summary(&id, crate::report::Flow::SketchEdit, report_json, BTreeMap::new(), &artefacts, None);
    let preview = Preview { href: summary.href.clone(), artefacts: summary.artefacts.clone() };
    s.0.results.put(id, Stored { summary, artefacts, expires: None });
    Ok(TemplateEdited { report, document, preview })
}

#[cfg(test)]
mod tests {
    use axum::body::Body;
    use axum::http::{header, Request, StatusCode};
    use glam::DVec2;
    use http_body_util::BodyExt;
    use serde_json::{json, Value};
    use tower::ServiceExt;

    use super::*;
    use crate::template::codec::decode;
    use crate::template::format::Template;
    use crate::template::sketch::{CanonicalView, SketchView};

    async fn call(s: &AppState, req: Request<Body>) -> (StatusCode, header::HeaderMap, Vec<u8>) {
        let resp = crate::app(s.clone()).oneshot(req).await.unwrap();
        let (parts, body) = resp.into_parts();
        (parts.status, parts.headers, body.collect().await.unwrap().to_bytes().to_vec())
    }

    fn post_edit(name: &str, edit: &Value, key: bool) -> Request<Body> {
        let mut req =
            Request::post(format!("/v1/templates/{name}/edits")).header(header::CONTENT_TYPE, "application/json");
        if key {
            req = req.header(header::AUTHORIZATION, "Bearer k");
        }
        req.body(Body::from(edit.to_string())).unwrap()
    }

    fn get(uri: &str) -> Request<Body> {
        Request::get(uri).body(Body::empty()).unwrap()
    }

    /// A write of a template document with the key: `PUT` to `name`, or `POST` a new one.
    fn write(method: &str, uri: &str, doc: &str) -> Request<Body> {
        Request::builder()
            .method(method)
            .uri(uri)
            .header(header::AUTHORIZATION, "Bearer k")
            .header(header::CONTENT_TYPE, "application/json")
            .body(Body::from(doc.to_owned()))
            .unwrap()
    }

    fn put(name: &str, doc: &str) -> Request<Body> {
        write("PUT", &format!("/v1/templates/{name}"), doc)
    }

    fn create(t: &Template) -> Request<Body> {
        write("POST", "/v1/templates", &t.to_json())
    }

    /// A node move: `(dx, dy)` pixels at 1 mm per pixel in `view`.
    fn move_node(view: &str, node: u32, dx: f64, dy: f64) -> Value {
        json!({
            "view": {"view": view, "metres_per_px": 0.001, "origin_px": [500.0, 500.0]},
            "edit": {"kind": "move_node", "node": node, "stroke": [[100.0, 100.0], [100.0 + dx, 100.0 + dy]]}
        })
    }

    fn json_of(bytes: &[u8]) -> Value {
        serde_json::from_slice(bytes).unwrap()
    }

    /// The schema errors of `instance` against the contract's component `name`.
    fn schema_errors(name: &str, instance: &Value) -> Vec<String> {
        let doc = serde_json::to_value(crate::api::openapi()).unwrap();
        let schema = json!({
            "$schema": "https://json-schema.org/draft/2020-12/schema",
            "$ref": format!("#/components/schemas/{name}"),
            "components": doc["components"],
        });
        let v = jsonschema::validator_for(&schema).unwrap();
        v.iter_errors(instance).take(10).map(|e| format!("{e} at {}", e.instance_path())).collect()
    }

    #[tokio::test]
    async fn an_edit_is_stored_as_the_next_version_round_trips_through_get_and_is_undone_by_a_put() {
        let (s, dir) = crate::tests::state();
        let edit = move_node("right", 17, 20.0, 1.0);
        // a write: the key is needed
        assert_eq!(call(&s, post_edit("straight-skirt", &edit, false)).await.0, StatusCode::UNAUTHORIZED);
        let (status, headers, body) = call(&s, post_edit("straight-skirt", &edit, true)).await;
        assert_eq!(status, StatusCode::CREATED, "{}", String::from_utf8_lossy(&body));
        assert_eq!(headers[header::LOCATION], "/v1/templates/straight-skirt?version=2");
        let answer: TemplateEdited = serde_json::from_slice(&body).unwrap();
        assert_eq!((answer.report.template.version, answer.report.based_on), (2, 1));
        assert_eq!(answer.report.moved_nodes, vec![17]);
        assert_eq!(answer.report.resolved, vec![Resolution::Released { node: 17, rule: "drop".into() }]);
        assert_eq!(answer.document["version"], 2);
        // the answer is what the contract says (and a planted violation is caught)
        let mut answer_json = json_of(&body);
        assert_eq!(schema_errors("TemplateEdited", &answer_json), Vec::<String>::new());
        answer_json["report"]["resolved"][0]["node"] = json!("seventeen");
        assert!(!schema_errors("TemplateEdited", &answer_json).is_empty());
        // the stored version is what the edit returned
        let (status, headers, stored) = call(&s, get("/v1/templates/straight-skirt?version=2")).await;
        assert_eq!((status, &headers["x-template-version"]), (StatusCode::OK, &"2".parse().unwrap()));
        assert_eq!(json_of(&stored), answer.document);
        let (_, headers, live) = call(&s, get("/v1/templates/straight-skirt")).await;
        assert_eq!((headers["x-template-version"].to_str().unwrap(), json_of(&live)), ("2", answer.document.clone()));
        // the node moved 20 mm along +z on the design body
        let body = &*builtin_body(&DesignBody::Reference).unwrap();
        let (v1, v2) = (
            s.0.store.get("straight-skirt", Some(1)).unwrap().1,
            Template::from_json(&String::from_utf8(stored).unwrap()).unwrap(),
        );
        let (m1, m2) =
            (decode(&v1, body, v1.defaults.relocation).unwrap(), decode(&v2, body, v2.defaults.relocation).unwrap());
        assert!((m2.positions[17] - m1.positions[17] - glam::DVec3::Z * 0.02).length() < 1e-9);
        // the preview's GLBs download
        assert_eq!(answer.preview.artefacts.len(), 2);
        for a in &answer.preview.artefacts {
            let (status, headers, bytes) = call(&s, get(&a.href)).await;
            assert_eq!(
                (status, headers[header::CONTENT_TYPE].to_str().unwrap()),
                (StatusCode::OK, "model/gltf-binary")
            );
            assert_eq!((&bytes[..4], bytes.len()), (&b"glTF"[..], a.bytes));
        }
        let (status, _, result) = call(&s, get(&answer.preview.href)).await;
        assert_eq!(status, StatusCode::OK);
        assert_eq!(json_of(&result)["report"], serde_json::to_value(&answer.report).unwrap());
        assert_eq!(schema_errors("GradeResult", &json_of(&result)), Vec::<String>::new());
        // undo: PUT of version 1 makes version 3, equal to version 1 but for its number
        let (_, _, old) = call(&s, get("/v1/templates/straight-skirt?version=1")).await;
        let (status, _, entry) = call(&s, put("straight-skirt", &String::from_utf8(old).unwrap())).await;
        assert_eq!((status, json_of(&entry)["version"].clone()), (StatusCode::OK, json!(3)));
        let (_, headers, live) = call(&s, get("/v1/templates/straight-skirt")).await;
        assert_eq!(headers["x-template-version"], "3");
        let v3 = Template::from_json(&String::from_utf8(live).unwrap()).unwrap();
        assert_eq!(v3, v1);
        assert_ne!(v3.nodes[17], v2.nodes[17]);
        // and an edit now applies to version 3
        let (status, _, body) = call(&s, post_edit("straight-skirt", &edit, true)).await;
        assert_eq!(status, StatusCode::CREATED);
        assert_eq!(json_of(&body)["report"]["based_on"], 3);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[tokio::test]
    async fn a_mirrored_edit_says_so_and_lands_on_both_sides() {
        let (s, dir) = crate::tests::state();
        let (status, _, body) = call(&s, post_edit("trousers", &move_node("front", 27, 10.0, 0.0), true)).await;
        assert_eq!(status, StatusCode::CREATED, "{}", String::from_utf8_lossy(&body));
        let answer: TemplateEdited = serde_json::from_slice(&body).unwrap();
        assert_eq!(answer.report.resolved, vec![Resolution::MirroredNode { node: 27, counterpart: 36 }]);
        assert_eq!(answer.report.moved_nodes, vec![27, 36]);
        let json = json_of(&body);
        assert_eq!(json["report"]["resolved"][0]["kind"], "mirrored_node");
        let _ = std::fs::remove_dir_all(dir);
    }

    #[tokio::test]
    async fn an_edit_is_made_on_the_templates_design_body() {
        let (s, dir) = crate::tests::state();
        // the skirt, declared designed on MakeHuman's base mesh
        let mut skirt = s.0.store.get("straight-skirt", None).unwrap().1;
        skirt.name = "base-skirt".into();
        skirt.design_body = Some(DesignBody::MakehumanBase);
        assert_eq!(call(&s, create(&skirt)).await.0, StatusCode::CREATED);
        let (status, _, body) = call(&s, post_edit("base-skirt", &move_node("right", 17, 20.0, 0.0), true)).await;
        assert_eq!(status, StatusCode::CREATED, "{}", String::from_utf8_lossy(&body));
        let answer: TemplateEdited = serde_json::from_slice(&body).unwrap();
        assert_eq!(answer.report.design_body, DesignBody::MakehumanBase);
        let edited = Template::from_json(&answer.document.to_string()).unwrap();
        assert_eq!(edited.design_body, Some(DesignBody::MakehumanBase), "kept by the edit");
        // 20 mm along +z on the base mesh, exactly; not so on the reference body
        let at = |t: &Template, which| {
            let body = builtin_body(&which).unwrap();
            decode(t, &body, t.defaults.relocation).unwrap().positions[17]
        };
        let moved = at(&edited, DesignBody::MakehumanBase) - at(&skirt, DesignBody::MakehumanBase);
        assert!((moved - glam::DVec3::Z * 0.02).length() < 1e-9, "{moved}");
        let elsewhere = at(&edited, DesignBody::Reference) - at(&skirt, DesignBody::Reference);
        assert!((elsewhere - glam::DVec3::Z * 0.02).length() > 1e-4, "{elsewhere}");
        let _ = std::fs::remove_dir_all(dir);
    }

    /// The skirt's front hem edge 17–18 in the front view at 1 mm per pixel, and a stroke over it
    /// with an X in its middle.
    fn looped_stroke() -> Value {
        let body = &*builtin_body(&DesignBody::Reference).unwrap();
        let skirt = crate::template::library::builtin().unwrap().remove(0);
        let m = decode(&skirt, body, skirt.defaults.relocation).unwrap();
        let view = SketchView { view: CanonicalView::Front, metres_per_px: 0.001, origin_px: [500.0, 500.0] };
        let (a, b) = (view.to_px(m.positions[17]), view.to_px(m.positions[18]));
        let at = |t: f64, up: f64| a.lerp(b, t) + DVec2::new(0.0, -up);
        let mut pts: Vec<DVec2> = (0..=16).map(|i| at(i as f64 / 40.0, 0.0)).collect();
        pts.extend([at(0.6, 10.0), at(0.5, 20.0), at(0.4, 10.0), at(0.6, -5.0)]);
        pts.extend((25..=40).map(|i| at(i as f64 / 40.0, 0.0)));
        let stroke: Vec<[f64; 2]> = pts.iter().map(|q| [q.x, q.y]).collect();
        json!({
            "view": {"view": "front", "metres_per_px": 0.001, "origin_px": [500.0, 500.0]},
            "edit": {"kind": "profile", "stroke": stroke}
        })
    }

    #[tokio::test]
    async fn every_refusal_is_a_problem_naming_the_constraint_and_what_breaks_it_and_stores_nothing() {
        let (s, dir) = crate::tests::state();
        // C6 needs a declared range: the trousers' knee within [0, 160] mm (measured 154.5)
        let (mut trousers, _) = (s.0.store.get("trousers", None).unwrap().1, ());
        trousers.ease_range_mm.insert("knee".into(), [0.0, 160.0]);
        assert_eq!(call(&s, put("trousers", &trousers.to_json())).await.0, StatusCode::OK);
        // symmetric: the right front hem node 30 mm off the left one's mirror image
        let (mut off, _) = (s.0.store.get("trousers", None).unwrap().1, ());
        off.name = "lopsided".into();
        off.nodes[36].alpha += 0.03;
        assert_eq!(call(&s, create(&off)).await.0, StatusCode::CREATED);
        // C12's ease: the left waist node lifted off the waist, kept …
        assert_eq!(
            call(&s, post_edit("straight-skirt", &move_node("front", 2, 0.0, -40.0), true)).await.0,
            StatusCode::CREATED
        );
        let cases: Vec<(&str, Value, u16, &str, &[&str])> = vec![
            ("straight-skirt", move_node("front", 18, -120.0, 0.0), 422, "constraint-c12-inside-body", &["node 18"]),
            // the lifted waist node 12 mm in: outside the body, but its arc to node 1 cuts in
            ("straight-skirt", move_node("front", 2, -12.0, 0.0), 422, "constraint-c12-inside-body", &["edge 7"]),
            ("lopsided", move_node("front", 27, 10.0, 0.0), 422, "constraint-symmetric", &["node 27", "left_front"]),
            // … then its neighbour too: the waist line no longer goes round the waist
            ("straight-skirt", move_node("front", 3, 0.0, -40.0), 422, "constraint-c12-negative-ease", &["`waist`"]),
            ("straight-skirt", looped_stroke(), 422, "constraint-c13-self-intersection", &["edge 38"]),
            (
                "straight-skirt",
                move_node("front", 17, 0.0, -600.0),
                422,
                "constraint-c13-self-intersection",
                &["panel `front`"],
            ),
            (
                "trousers",
                move_node("front", 26, -60.0, 0.0),
                422,
                "constraint-c6-ease-range",
                &["`knee`", "[0, 160] mm"],
            ),
            (
                "straight-skirt",
                move_node("front", 0, 0.0, 250.0),
                422,
                "constraint-c8-girth-order",
                &["`waist`", "`hip`", "node 0"],
            ),
            ("straight-skirt", move_node("right", 1, 5.0, 0.0), 422, "edit-overridden", &["node 1", "`waist`"]),
            ("straight-skirt", move_node("front", 99, 5.0, 0.0), 422, "edit-no-such-node", &["node 99"]),
            ("straight-skirt", move_node("front", 17, 1e9, 0.0), 422, "edit-out-of-reach", &["node 17"]),
            ("straight-skirt", move_node("front", 17, 0.0, 0.0), 400, "sketch-stroke", &["no length"]),
            ("nope", move_node("front", 1, 5.0, 0.0), 404, "not-found", &["nope"]),
        ];
        for (name, edit, status, slug, named) in cases {
            let before = s.0.store.get(name, None).ok().map(|e| e.0);
            let (got, headers, body) = call(&s, post_edit(name, &edit, true)).await;
            let problem = json_of(&body);
            assert_eq!(got.as_u16(), status, "{slug}: {problem}");
            assert_eq!(headers[header::CONTENT_TYPE], crate::problem::PROBLEM_JSON);
            assert!(problem["type"].as_str().unwrap().ends_with(slug), "{slug}: {problem}");
            let detail = problem["detail"].as_str().unwrap();
            for n in named {
                assert!(detail.contains(n), "{slug}: `{n}` not in {detail}");
            }
            assert_eq!(s.0.store.get(name, None).ok().map(|e| e.0), before, "{slug}: nothing stored");
        }
        // a field the edit does not have
        let mut bad = move_node("front", 17, 5.0, 0.0);
        bad["colour"] = json!("red");
        assert_eq!(call(&s, post_edit("straight-skirt", &bad, true)).await.0, StatusCode::BAD_REQUEST);
        let _ = std::fs::remove_dir_all(dir);
    }
}
