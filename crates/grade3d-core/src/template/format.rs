//! The garment feature template document (seed 000 §3, Table 1) and its
//! validation.
//!
//! A template is a coarse triangle mesh `M^f = (K^f, V^f)` whose nodes are
//! tied to feature points of the body:
//! * **nodes** — `(j, α, β, γ)` of seed 000 Eq. (1), plus the plain offset
//!   `d` of Eq. (2) (kept for comparison) and the node's position on the
//!   reference body (needed by Eq. (5) to move profiles);
//! * **edge table** — start node, end node, attached profile points
//!   (absolute coordinates on the reference body, as the paper stores them);
//! * **face table** — three edges and their directions (+1 when the face
//!   runs the edge from its start to its end node, −1 otherwise);
//! * **panels** (faces of each pattern piece, grain line, quantity),
//!   **seams** (edge chains sewn together), **notches**, ease and default
//!   grading options.
//!
//! [`Template::validate`] checks everything a decoder relies on and names
//! the offending element: unknown feature IDs, dangling references,
//! face edges that do not form a directed triangle, edges shared by more
//! than two faces or used twice in the same direction, non-finite
//! numbers, and schema versions from the future.

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use crate::body::vocab::{CurveId, PointId, VOCABULARY_VERSION};
use crate::geom::mesh::FaceId;
use crate::geom::topology::{check_edge_uses, EdgeUse, TopologyError};

pub use super::from_garment::DesignBody;

/// Version of the template schema this build reads and writes.
pub const SCHEMA_VERSION: u32 = 1;

/// Identifier of the schema (the `schema` field).
pub const SCHEMA_ID: &str = "grade3d/garment-template";

/// A node of the template (seed 000 Eq. 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Node {
    /// Feature point `q_j` the node is tied to.
    pub point: PointId,
    /// Offset along the surface normal `n(q_j)`, m.
    pub alpha: f64,
    /// Offset along `t(f1)`, m.
    pub beta: f64,
    /// Offset along `t(f2)`, m.
    pub gamma: f64,
    /// Eq. (2) offset `d`, m (world axes of the reference body).
    pub offset: [f64; 3],
    /// Position on the reference body, m.
    pub reference: [f64; 3],
    /// For a ring node ([`super::girth`]): where it sits along its girth
    /// from its feature point, as a signed fraction `σ` of the bridged
    /// girth's length `L` (in the girth's walking direction): decoding
    /// places it at arc parameter `s(q_j) + σ·L` of the eased girth, so it
    /// grades in proportion to the girth. A seam that crosses the girth a
    /// little way from a feature point takes that point's ring node
    /// (issue #18: a princess seam 20 mm from the bust's oblique point);
    /// at the point itself the seam's crossing jumped along the ring, and
    /// the seam kinked there. Absent: 0, the node at its point.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ring_shift: Option<f64>,
}

/// A row of the edge table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Edge {
    /// Start node index.
    pub start: u32,
    /// End node index.
    pub end: u32,
    /// Attached profile points `Q_0..Q_{n−1}` on the reference body, m;
    /// empty when the edge has no profile. `Q_0` is the start node and
    /// `Q_{n−1}` the end node.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub profile: Vec<[f64; 3]>,
}

/// A row of the face table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Face {
    /// The three edges, in counter-clockwise order seen from outside.
    pub edges: [u32; 3],
    /// +1 where the face runs the edge start → end, −1 otherwise.
    pub directions: [i8; 3],
}

/// A grain line: from one node towards another (on the reference body),
/// and the piece's stack point.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrainLine {
    /// Node at the start of the grain arrow.
    pub from: u32,
    /// Node at its end.
    pub to: u32,
    /// The piece's stack point: the node a graded nest stacks its sizes at
    /// (`crate::pattern::assemble` places it at the origin). Absent: `from`.
    /// A pattern maker grades a piece out from a point inside it, on the
    /// waist, hip or bust line; the grain arrow runs the piece's length,
    /// so that its direction is read over a long span.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stack: Option<u32>,
}

impl GrainLine {
    /// The stack point's node: [`Self::stack`], else [`Self::from`].
    pub fn stack_node(&self) -> u32 {
        self.stack.unwrap_or(self.from)
    }
}

/// A pattern piece.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Panel {
    /// Piece name (unique).
    pub name: String,
    /// Faces of the piece.
    pub faces: Vec<u32>,
    /// Grain line.
    pub grain: GrainLine,
    /// Pieces to cut.
    pub quantity: u32,
}

/// Two edge chains sewn together.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Seam {
    /// Seam name (unique).
    pub name: String,
    /// First side: panel name.
    pub panel_a: String,
    /// Second side: panel name.
    pub panel_b: String,
    /// The edges along the seam, in order.
    pub edges: Vec<u32>,
}

/// A notch on an edge.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Notch {
    /// What the notch marks (e.g. `hip`).
    pub name: String,
    /// The node it sits at.
    pub node: u32,
}

/// A dart: a wedge sewn closed inside a panel (seed 002 §6). The template
/// gives its centre line as a chain of edges from a node on the panel's
/// outline (the dart's opening) to an interior node (its apex); the panel
/// is slit along it before flattening, so the wedge opens by what the
/// surface's curvature needs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Dart {
    /// Dart name (unique).
    pub name: String,
    /// Panel it lies in.
    pub panel: String,
    /// Edges from the outline to the apex, in order.
    pub edges: Vec<u32>,
}

/// A node that hangs straight between two others: cloth falls in a straight
/// line from a girth to the next one below, bridging a narrower girth
/// between (a skirt from a belly over the hip, a trouser leg from the thigh
/// past the knee) unless held in. After relocation, if the point of the
/// segment `upper → lower` at the node's height lies further from the body
/// than the node (along the node's offset from its closest body point), the
/// node moves there; the profiles of its edges follow by Eq. (5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hang {
    /// The node that may move.
    pub node: u32,
    /// The node it hangs from.
    pub upper: u32,
    /// The node its line runs to.
    pub lower: u32,
}

/// A node that drops from another, perpendicular to a girth: cloth falls
/// from a girth it is held at (a straight skirt's hem from the hip line).
/// After the ring nodes are placed, the node goes to
///
/// ```text
/// p = p_from − L·u + F·o
/// ```
///
/// `u` the unit normal of the girth's plane pointing up the body (from the
/// crotch towards the back neck point); `o` the unit direction, within the plane,
/// from the centre `c` of every drop's `from` on that girth to `p_from`;
/// `L` [`Drop::length_m`], `F` [`Drop::flare_m`]. Eq. (1) carries a long
/// offset (35 cm) in its feature point's frame, where a tangent a few
/// degrees off the vertical moves the hem by centimetres (a short man's
/// centre back curving under the seat threw the skirt's back hem 13 cm
/// forward, between his knees: pop09); the girth's plane is that body's own
/// level. Rotation- and translation-covariant (no world axis).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Drop {
    /// The node placed.
    pub node: u32,
    /// The node it drops from.
    pub from: u32,
    /// The girth whose plane it drops perpendicular to.
    pub girth: CurveId,
    /// Drop `L` below `from`, m.
    pub length_m: f64,
    /// Outward flare `F` beyond `from`, within the girth's plane, m.
    pub flare_m: f64,
}

/// A node placed along a body feature curve (an armhole node on the
/// armscye): at the fraction [`OnCurve::fraction`] of the arc from the
/// curve point nearest `from` to the curve point nearest `to`, taking the
/// one of the two arcs between them whose midpoint lies nearer `via`, then
/// eased outwards from the loop's centroid `c` within the curve's plane
/// (normal `n`):
///
/// ```text
/// s = s_from + f·Δs,   d = γ(s) − c,   p = γ(s) + r·(d − (d·n)n)/|d − (d·n)n| + m·ν
/// ```
///
/// `γ` the curve as the body derives it, `Δs` the signed arc length of the
/// chosen arc, `f` the fraction, `r` [`OnCurve::radial_m`], `m`
/// [`OnCurve::normal_m`] and `ν = ±n`, the plane's normal turned away from
/// `via` (from the torso to the arm for an armscye and a chest point). Eq. (1) ties a
/// node to one feature point by a fixed offset in that point's frame; an
/// armhole node about 80 mm from the armpit point then decodes inside a
/// fuller chest (ASTM size 20: 28.6 mm inside). The curve is the body's
/// own, so the node follows it on every body. Rotation- and
/// translation-covariant (no world axis). Applied after Eq. (1), before the
/// ring nodes, drops and hangs; a body that lacks the curve or a point
/// keeps the Eq. (1) position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OnCurve {
    /// The node placed.
    pub node: u32,
    /// The closed feature curve it lies on.
    pub curve: CurveId,
    /// Feature point whose nearest curve point starts the arc.
    pub from: PointId,
    /// Feature point whose nearest curve point ends the arc.
    pub to: PointId,
    /// Of the two arcs between them, the one whose midpoint is nearer this point.
    pub via: PointId,
    /// Fraction of the arc from `from`, in `[0, 1]`.
    pub fraction: f64,
    /// Outward offset from the curve, m.
    pub radial_m: f64,
    /// Offset along the curve plane's normal turned away from `via`, m: an
    /// armhole authored from a garment (issue #18) lies off the armscye's
    /// plane, towards the torso. Default 0 (the library's armholes).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub normal_m: f64,
}

/// Whether a flag is off (left out of a document).
fn is_false(x: &bool) -> bool {
    !*x
}

/// Whether an offset is exactly zero (left out of a document).
fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// A node hanging below a girth, away from the body: cloth that falls from
/// the girth it is held at and does not follow the legs (a skirt or a
/// dress below the hip, issue #18: authored from a garment). Placed at
///
/// ```text
/// s = s_from + f·Δs,   p = ĉ(s) + r·û(s) − L·u
/// ```
///
/// `ĉ` the girth bridged as a tape bridges it ([`super::girth::bridged`]),
/// `Δs` the signed arc length of the shorter arc from the loop point
/// nearest `from` to the one nearest `to`, `f` [`Below::fraction`], `û(s)`
/// the outward direction within the girth's plane from the bridged loop's
/// centroid, `r` [`Below::radial_m`], `u` the plane's unit normal up the
/// body ([`super::codec::drop_axis`]) and `L` [`Below::drop_m`] (graded
/// with the body's leg length, [`Below::leg_m`]). Eq. (1)
/// ties such a node to the nearest feature point, on a knee or an ankle:
/// on a body whose legs stand wider the hem would follow them, and the
/// cloth between would stretch (10–20 % p95 strain on the fixture bodies,
/// measured). Rotation- and translation-covariant (no world axis). Applied
/// after Eq. (1) and the on-curve placements; a body that lacks the girth
/// or a point keeps the Eq. (1) position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Below {
    /// The node placed.
    pub node: u32,
    /// The girth it hangs from.
    pub girth: CurveId,
    /// Feature point on the girth where the arc starts.
    pub from: PointId,
    /// Feature point on the girth where the arc ends.
    pub to: PointId,
    /// Fraction of the arc from `from`, in `[0, 1]` (of the angle, with
    /// [`Below::by_angle`]).
    pub fraction: f64,
    /// Whether [`Below::fraction`] divides the angle from `from` to `to`
    /// (the shorter way) as seen from the bridged girth's centroid within
    /// its plane, `s` being the loop's point in the direction `θ_from +
    /// f·Δθ`, rather than the arc length between them: the hem of a skirt
    /// keeps its direction around the body on a figure whose girth is
    /// shaped unlike the design body's (authoring sets it,
    /// [`super::from_garment`]). Default false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub by_angle: bool,
    /// Outward offset from the bridged girth within its plane, m.
    pub radial_m: f64,
    /// Drop below the girth's plane on the design body, m.
    pub drop_m: f64,
    /// The design body's distance from the girth's plane down to its ankle
    /// girths (the mean of their centroids, along `u`), m; 0: none. Where
    /// both bodies have it the drop grades in proportion, `L = drop_m ·
    /// D / leg_m` (`D` the body's own): a hem at mid-calf stays at mid-calf
    /// (an ankle-length skirt authored on a 1.67 m body reached into a
    /// 1.55 m body's feet, measured).
    #[serde(default)]
    pub leg_m: f64,
}

/// A node lofted between two girths (issue #18: authored from a garment;
/// the band of a skirt between the hip and the waist, a bodice's between
/// the bust and the waist). With `A`, `B` the lower and upper girth
/// bridged ([`super::girth::bridged`]), each walked from the loop point
/// nearest its start point in its own direction (the vocabulary orients
/// every girth alike), `L_A`, `L_B` their lengths and `c_A`, `c_B` their
/// centroids:
///
/// ```text
/// a = A(s_A + f·L_A),  b = B(s_B + f·L_B),  q = a + h·(b − a),  c = c_A + h·(c_B − c_A)
/// e = (c_B − c_A)/|c_B − c_A|,  d = (q − c) − ((q − c)·e)·e,  p = q + r·d/|d|
/// ```
///
/// `f` [`Between::fraction`], `h` [`Between::height`], `r`
/// [`Between::radial_m`]. Eq. (1) ties a node to one feature point; a band
/// 15 cm tall has most of its nodes 5–15 cm from the nearest, and on a body
/// whose back curves more the frame there turns and carries them
/// centimetres off (an edge of the helper-skirt's back grew 4.8 times on a
/// fixture body, measured). Rotation- and translation-covariant. Applied
/// after Eq. (1); a body that lacks a girth or a point keeps the Eq. (1)
/// position.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Between {
    /// The node placed.
    pub node: u32,
    /// The lower girth.
    pub lower: CurveId,
    /// Where the lower girth's walk starts (a feature point on it).
    pub lower_start: PointId,
    /// The upper girth.
    pub upper: CurveId,
    /// Where the upper girth's walk starts.
    pub upper_start: PointId,
    /// Fraction of the girths' length from their starts, in `[0, 1]`.
    pub fraction: f64,
    /// Height between them: 0 on the lower, 1 on the upper.
    pub height: f64,
    /// Outward offset from the lofted girths, m.
    pub radial_m: f64,
    /// Where the lower girth's point `a` lies between two of that girth's
    /// feature points; when given, it replaces `a = A(s_A + f·L_A)`
    /// ([`Bracket`]). Absent in templates authored before it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lower_bracket: Option<Bracket>,
    /// Where the upper girth's point `b` lies between two of its feature
    /// points, as [`Self::lower_bracket`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub upper_bracket: Option<Bracket>,
}

/// A point of a girth placed between two of its feature points (issue #18:
/// a lofted node follows the feature points on either side of it, as a
/// spaced ring node does, not the arc fraction of the whole girth from its
/// midline start, which parts from the ring nodes on a body whose girths
/// differ in shape — 17–23 mm on a figure with a belly, measured). With
/// `s_from`, `s_to` the arc parameters of the loop points nearest the two
/// feature points, walked in the girth's direction (the vocabulary orients
/// every girth alike), and `L` its length:
///
/// ```text
/// x = A(s_from + t·((s_to − s_from) mod L))
/// ```
///
/// `t` [`Bracket::fraction`]. Continuous as a node moves past a feature
/// point (`t = 1` of one bracket is `t = 0` of the next).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Bracket {
    /// The feature point the walk starts at.
    pub from: PointId,
    /// The next feature point along the girth's direction.
    pub to: PointId,
    /// Fraction of the arc from `from` to `to`, in `[0, 1]`.
    pub fraction: f64,
}

/// Which relocation equation a decode uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Relocation {
    /// Seed 000 Eq. (1): offsets in the local frame (default).
    #[default]
    Eq1Frame,
    /// Seed 000 Eq. (2): plain world offsets (for comparison only).
    Eq2Offset,
}

/// Default grading options stored with a template.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GradingDefaults {
    /// Subdivision levels. Default 3.
    pub levels: u32,
    /// Clearance kept between garment and body, mm. Default 3.
    pub clearance_mm: f64,
    /// Seam allowance of the pattern pieces, mm. Default 10.
    pub seam_allowance_mm: f64,
    /// Relocation equation. Default Eq. (1).
    pub relocation: Relocation,
    /// Found darts follow a pattern maker's rules
    /// ([`crate::pattern::darts::DartGuides`]: along the grain and opening
    /// across it, in mirrored pairs on a piece that is its own mirror image,
    /// short of the girth lines, kept out of the region hanging below the
    /// lowest girth unless a piece needs them there). Default false, as in
    /// documents without it: the built-in templates, whose found darts top
    /// up the darts they declare (under the rules the fitted bodice's graded
    /// shoulder steps vary by up to 5.2 mm where 2.9 mm is allowed: its
    /// darts are to be drafted as declared ones first, issue #18's notes).
    /// Templates authored from a garment or from curves, which declare no
    /// darts, set it.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub guided_darts: bool,
}

impl Default for GradingDefaults {
    fn default() -> Self {
        Self {
            levels: 3,
            clearance_mm: 3.0,
            seam_allowance_mm: 10.0,
            relocation: Relocation::Eq1Frame,
            guided_darts: false,
        }
    }
}

/// A garment feature template document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Template {
    /// Always [`SCHEMA_ID`].
    pub schema: String,
    /// Schema version ([`SCHEMA_VERSION`]).
    pub schema_version: u32,
    /// Feature vocabulary version the node IDs belong to.
    pub vocabulary: u32,
    /// Template name (a slug).
    pub name: String,
    /// Template version (increases with every change).
    pub version: u32,
    /// Human description.
    #[serde(default)]
    pub description: String,
    /// Ease at each girth the style defines, mm (garment girth − body girth).
    #[serde(default)]
    pub ease_mm: BTreeMap<String, f64>,
    /// Seed 002 C6: per girth (by `ease_mm` name) the range `[min, max]` its
    /// measured ease must stay within under sketch edits, mm
    /// ([`super::edit`]); absent: no range.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub ease_range_mm: BTreeMap<String, [f64; 2]>,
    /// The body the template was designed on, where sketch edits apply
    /// ([`super::edit`]); `None`: the reference mannequin
    /// ([`super::library::reference_body`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub design_body: Option<DesignBody>,
    /// Nodes `V^f`.
    pub nodes: Vec<Node>,
    /// Edge table.
    pub edges: Vec<Edge>,
    /// Face table.
    pub faces: Vec<Face>,
    /// Pattern pieces.
    pub panels: Vec<Panel>,
    /// Seams.
    #[serde(default)]
    pub seams: Vec<Seam>,
    /// Notches.
    #[serde(default)]
    pub notches: Vec<Notch>,
    /// Darts.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub darts: Vec<Dart>,
    /// Nodes that drop from another perpendicular to a girth (applied
    /// before the hangs).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub drops: Vec<Drop>,
    /// Nodes placed along a body curve (applied after Eq. (1), before the
    /// ring nodes).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub on_curve: Vec<OnCurve>,
    /// Nodes lofted between two girths (applied after the on-curve placements).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub between: Vec<Between>,
    /// Nodes hanging below a girth (applied after the on-curve placements).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub below: Vec<Below>,
    /// Nodes that hang straight between two others (applied in order).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hangs: Vec<Hang>,
    /// Panels that are mirror images of each other on a symmetric body,
    /// `[first, second]` (a left and a right trouser front): darts found on
    /// the first are mirrored onto the second (issue #14, item 2).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub mirror_pairs: Vec<[String; 2]>,
    /// Default grading options.
    #[serde(default)]
    pub defaults: GradingDefaults,
}

/// What is wrong with a template.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TemplateError {
    /// Not parseable (syntax, wrong types, unknown fields, unknown feature ID).
    #[error("template JSON: {0}")]
    Syntax(String),
    /// The document violates the JSON Schema (`templates/schema/`).
    #[error("template does not match its JSON Schema: {0}")]
    Schema(String),
    /// Not a template document.
    #[error("`schema` is `{0}`, expected `{SCHEMA_ID}`")]
    NotATemplate(String),
    /// Written by a newer schema.
    #[error("schema version {found} is newer than this service's {supported}")]
    FutureSchema {
        /// Version in the document.
        found: u32,
        /// Newest supported.
        supported: u32,
    },
    /// Written against a newer feature vocabulary.
    #[error("vocabulary version {found} is newer than this service's {supported}")]
    FutureVocabulary {
        /// Version in the document.
        found: u32,
        /// Newest supported.
        supported: u32,
    },
    /// Empty name or no nodes/faces.
    #[error("template is empty: {0}")]
    Empty(&'static str),
    /// A non-finite number.
    #[error("{element} has a non-finite number")]
    NonFinite {
        /// Which element (`node 3`, `edge 7 profile`, …).
        element: String,
    },
    /// An edge names a node that does not exist, or the same node twice.
    #[error("edge {edge}: {reason}")]
    BadEdge {
        /// The edge.
        edge: u32,
        /// What is wrong.
        reason: String,
    },
    /// A face names an edge that does not exist.
    #[error("face {face} names edge {edge}, which does not exist")]
    MissingEdge {
        /// The face.
        face: u32,
        /// The edge it names.
        edge: u32,
    },
    /// A face's edges and directions do not form a directed triangle.
    #[error("face {face}: edges and directions do not form a directed triangle")]
    InconsistentDirections {
        /// The face.
        face: u32,
    },
    /// Not an oriented manifold: a template edge (by id) of three or more
    /// faces, or one run twice in the same direction.
    #[error(transparent)]
    Topology(#[from] TopologyError<u32>),
    /// A panel, seam, notch or grain line refers to something missing.
    #[error("{element}: {reason}")]
    BadReference {
        /// Which element.
        element: String,
        /// What is wrong.
        reason: String,
    },
}

/// The JSON Schema of the template document.
pub const SCHEMA_JSON: &str = include_str!("../../../../templates/schema/garment-template.schema.json");

/// Checks a parsed document against [`SCHEMA_JSON`]; the error lists the
/// first few violations with their JSON pointers.
pub fn check_schema(doc: &serde_json::Value) -> Result<(), TemplateError> {
    static VALIDATOR: std::sync::OnceLock<Result<jsonschema::Validator, String>> = std::sync::OnceLock::new();
    let v = VALIDATOR
        .get_or_init(|| {
            let schema: serde_json::Value = serde_json::from_str(SCHEMA_JSON).map_err(|e| e.to_string())?;
            jsonschema::validator_for(&schema).map_err(|e| e.to_string())
        })
        .as_ref()
        .map_err(|e| TemplateError::Schema(format!("the schema itself is invalid: {e}")))?;
    let errors: Vec<String> =
        v.iter_errors(doc).take(5).map(|e| format!("{} (at `{}`)", e, e.instance_path())).collect();
    if errors.is_empty() {
        Ok(())
    } else {
        Err(TemplateError::Schema(errors.join("; ")))
    }
}

fn finite3(a: &[f64; 3]) -> bool {
    a.iter().all(|x| x.is_finite())
}

impl Template {
    /// Parses and validates a template document.
    pub fn from_json(text: &str) -> Result<Self, TemplateError> {
        // Read the version fields first so that a future document gets the
        // right error even if its body does not parse with this schema.
        #[derive(Deserialize)]
        struct Head {
            schema: Option<String>,
            schema_version: Option<u32>,
            vocabulary: Option<u32>,
        }
        let head: Head = serde_json::from_str(text).map_err(|e| TemplateError::Syntax(e.to_string()))?;
        if let Some(s) = &head.schema {
            if s != SCHEMA_ID {
                return Err(TemplateError::NotATemplate(s.clone()));
            }
        }
        if let Some(v) = head.schema_version.filter(|&v| v > SCHEMA_VERSION) {
            return Err(TemplateError::FutureSchema { found: v, supported: SCHEMA_VERSION });
        }
        if let Some(v) = head.vocabulary.filter(|&v| v > VOCABULARY_VERSION) {
            return Err(TemplateError::FutureVocabulary { found: v, supported: VOCABULARY_VERSION });
        }
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| TemplateError::Syntax(e.to_string()))?;
        check_schema(&value)?;
        let t: Template = serde_json::from_value(value).map_err(|e| TemplateError::Syntax(e.to_string()))?;
        t.validate()?;
        Ok(t)
    }

    /// Serialises (pretty JSON, stable order).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default() + "\n"
    }

    /// The three node indices of a face, in its orientation.
    pub fn face_nodes(&self, f: usize) -> [u32; 3] {
        let face = &self.faces[f];
        let tail = |k: usize| {
            let e = &self.edges[face.edges[k] as usize];
            if face.directions[k] > 0 {
                e.start
            } else {
                e.end
            }
        };
        [tail(0), tail(1), tail(2)]
    }

    /// Checks every invariant a decoder relies on.
    pub fn validate(&self) -> Result<(), TemplateError> {
        if self.schema != SCHEMA_ID {
            return Err(TemplateError::NotATemplate(self.schema.clone()));
        }
        if self.schema_version > SCHEMA_VERSION {
            return Err(TemplateError::FutureSchema { found: self.schema_version, supported: SCHEMA_VERSION });
        }
        if self.vocabulary > VOCABULARY_VERSION {
            return Err(TemplateError::FutureVocabulary { found: self.vocabulary, supported: VOCABULARY_VERSION });
        }
        if self.name.trim().is_empty() {
            return Err(TemplateError::Empty("no name"));
        }
        if self.nodes.is_empty() || self.faces.is_empty() {
            return Err(TemplateError::Empty("no nodes or no faces"));
        }
        for (girth, &[lo, hi]) in &self.ease_range_mm {
            if !(lo.is_finite() && hi.is_finite() && lo <= hi) {
                return Err(TemplateError::BadReference {
                    element: format!("ease range of `{girth}`"),
                    reason: format!("[{lo}, {hi}] mm is not a finite range with min ≤ max"),
                });
            }
        }
        for (i, n) in self.nodes.iter().enumerate() {
            if ![n.alpha, n.beta, n.gamma].iter().all(|x| x.is_finite())
                || !finite3(&n.offset)
                || !finite3(&n.reference)
            {
                return Err(TemplateError::NonFinite { element: format!("node {i}") });
            }
        }
        let nn = self.nodes.len() as u32;
        for (i, e) in self.edges.iter().enumerate() {
            let edge = i as u32;
            if e.start >= nn || e.end >= nn {
                return Err(TemplateError::BadEdge { edge, reason: format!("node out of range ({} nodes)", nn) });
            }
            if e.start == e.end {
                return Err(TemplateError::BadEdge { edge, reason: "starts and ends at the same node".into() });
            }
            if !e.profile.iter().all(finite3) {
                return Err(TemplateError::NonFinite { element: format!("edge {i} profile") });
            }
            if e.profile.len() == 1 {
                return Err(TemplateError::BadEdge { edge, reason: "a profile needs at least two points".into() });
            }
        }
        // faces: edges exist, form a directed triangle; edge use counts
        let mut uses: Vec<(u32, EdgeUse)> = Vec::with_capacity(3 * self.faces.len());
        for (f, face) in self.faces.iter().enumerate() {
            let fid = f as u32;
            for &e in &face.edges {
                if e as usize >= self.edges.len() {
                    return Err(TemplateError::MissingEdge { face: fid, edge: e });
                }
            }
            if face.directions.iter().any(|&d| d != 1 && d != -1) {
                return Err(TemplateError::InconsistentDirections { face: fid });
            }
            let ends = |k: usize| {
                let e = &self.edges[face.edges[k] as usize];
                if face.directions[k] > 0 {
                    (e.start, e.end)
                } else {
                    (e.end, e.start)
                }
            };
            let (a, b, c) = (ends(0), ends(1), ends(2));
            if a.1 != b.0 || b.1 != c.0 || c.1 != a.0 || a.0 == b.0 || b.0 == c.0 || a.0 == c.0 {
                return Err(TemplateError::InconsistentDirections { face: fid });
            }
            for k in 0..3 {
                let forward = face.directions[k] > 0;
                uses.push((face.edges[k], EdgeUse { face: FaceId(fid), corner: k as u8, forward }));
            }
        }
        check_edge_uses(uses)?;
        // panels
        let mut names = BTreeSet::new();
        let mut owner: BTreeMap<u32, &str> = BTreeMap::new();
        for p in &self.panels {
            if !names.insert(p.name.as_str()) {
                return Err(TemplateError::BadReference {
                    element: format!("panel `{}`", p.name),
                    reason: "duplicate name".into(),
                });
            }
            for &f in &p.faces {
                if f as usize >= self.faces.len() {
                    return Err(TemplateError::BadReference {
                        element: format!("panel `{}`", p.name),
                        reason: format!("face {f} does not exist"),
                    });
                }
                if let Some(other) = owner.insert(f, &p.name) {
                    return Err(TemplateError::BadReference {
                        element: format!("panel `{}`", p.name),
                        reason: format!("face {f} also belongs to panel `{other}`"),
                    });
                }
            }
            if p.grain.from >= nn || p.grain.to >= nn || p.grain.from == p.grain.to {
                return Err(TemplateError::BadReference {
                    element: format!("panel `{}` grain line", p.name),
                    reason: "needs two distinct existing nodes".into(),
                });
            }
            if p.grain.stack.is_some_and(|s| s >= nn) {
                return Err(TemplateError::BadReference {
                    element: format!("panel `{}` grain line", p.name),
                    reason: "its stack point is not an existing node".into(),
                });
            }
        }
        if let Some(f) = (0..self.faces.len() as u32).find(|f| !owner.contains_key(f)) {
            return Err(TemplateError::BadReference {
                element: format!("face {f}"),
                reason: "belongs to no panel".into(),
            });
        }
        for d in &self.darts {
            let bad = |reason: String| TemplateError::BadReference { element: format!("dart `{}`", d.name), reason };
            if !names.contains(d.panel.as_str()) {
                return Err(bad(format!("panel `{}` does not exist", d.panel)));
            }
            if d.edges.is_empty() {
                return Err(bad("has no edges".into()));
            }
            if let Some(&e) = d.edges.iter().find(|&&e| e as usize >= self.edges.len()) {
                return Err(bad(format!("edge {e} does not exist")));
            }
        }
        for d in &self.drops {
            let bad = |reason: &str| TemplateError::BadReference {
                element: format!("drop of node {}", d.node),
                reason: reason.into(),
            };
            if [d.node, d.from].iter().any(|&v| v as usize >= self.nodes.len()) || d.node == d.from {
                return Err(bad("needs two distinct existing nodes"));
            }
            if !(d.length_m.is_finite() && d.flare_m.is_finite()) {
                return Err(bad("length and flare must be finite"));
            }
        }
        for c in &self.on_curve {
            let bad = |reason: &str| TemplateError::BadReference {
                element: format!("on-curve placement of node {}", c.node),
                reason: reason.into(),
            };
            if c.node as usize >= self.nodes.len() {
                return Err(bad("needs an existing node"));
            }
            if !(c.fraction.is_finite()
                && (0.0..=1.0).contains(&c.fraction)
                && c.radial_m.is_finite()
                && c.normal_m.is_finite())
            {
                return Err(bad("fraction must lie in [0, 1] and the offset be finite"));
            }
            if c.from == c.to {
                return Err(bad("needs two distinct feature points"));
            }
        }
        for b in &self.between {
            let bad = |reason: &str| TemplateError::BadReference {
                element: format!("between-girths placement of node {}", b.node),
                reason: reason.into(),
            };
            if b.node as usize >= self.nodes.len() {
                return Err(bad("needs an existing node"));
            }
            let finite = b.fraction.is_finite() && b.height.is_finite() && b.radial_m.is_finite();
            if !(finite && (0.0..=1.0).contains(&b.fraction)) {
                return Err(bad("fraction must lie in [0, 1] and height and offset be finite"));
            }
            if b.lower == b.upper {
                return Err(bad("needs two distinct girths"));
            }
            for k in [b.lower_bracket, b.upper_bracket].into_iter().flatten() {
                if !(k.fraction.is_finite() && (0.0..=1.0).contains(&k.fraction)) {
                    return Err(bad("a bracket's fraction must lie in [0, 1]"));
                }
                if k.from == k.to {
                    return Err(bad("a bracket needs two distinct feature points"));
                }
            }
        }
        for b in &self.below {
            let bad = |reason: &str| TemplateError::BadReference {
                element: format!("below-girth placement of node {}", b.node),
                reason: reason.into(),
            };
            if b.node as usize >= self.nodes.len() {
                return Err(bad("needs an existing node"));
            }
            let finite =
                b.fraction.is_finite() && b.radial_m.is_finite() && b.drop_m.is_finite() && b.leg_m.is_finite();
            if !(finite && (0.0..=1.0).contains(&b.fraction) && b.leg_m >= 0.0) {
                return Err(bad("fraction must lie in [0, 1] and the offsets be finite"));
            }
            if b.from == b.to {
                return Err(bad("needs two distinct feature points"));
            }
        }
        for h in &self.hangs {
            let ids = [h.node, h.upper, h.lower];
            if ids.iter().any(|&v| v as usize >= self.nodes.len()) || h.node == h.upper || h.node == h.lower {
                return Err(TemplateError::BadReference {
                    element: format!("hang of node {}", h.node),
                    reason: "needs three distinct existing nodes".into(),
                });
            }
        }
        let mut paired = std::collections::BTreeSet::new();
        for [a, b] in &self.mirror_pairs {
            let bad =
                |reason: String| TemplateError::BadReference { element: format!("mirror pair `{a}`/`{b}`"), reason };
            for side in [a, b] {
                if !names.contains(side.as_str()) {
                    return Err(bad(format!("panel `{side}` does not exist")));
                }
                if !paired.insert(side.as_str()) {
                    return Err(bad(format!("panel `{side}` is in more than one pair, or paired with itself")));
                }
            }
        }
        for s in &self.seams {
            for side in [&s.panel_a, &s.panel_b] {
                if !names.contains(side.as_str()) {
                    return Err(TemplateError::BadReference {
                        element: format!("seam `{}`", s.name),
                        reason: format!("panel `{side}` does not exist"),
                    });
                }
            }
            if s.edges.is_empty() {
                return Err(TemplateError::BadReference {
                    element: format!("seam `{}`", s.name),
                    reason: "has no edges".into(),
                });
            }
            for &e in &s.edges {
                if e as usize >= self.edges.len() {
                    return Err(TemplateError::BadReference {
                        element: format!("seam `{}`", s.name),
                        reason: format!("edge {e} does not exist"),
                    });
                }
            }
        }
        for n in &self.notches {
            if n.node >= nn {
                return Err(TemplateError::BadReference {
                    element: format!("notch `{}`", n.name),
                    reason: format!("node {} does not exist", n.node),
                });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-triangle template, valid.
    fn tiny() -> Template {
        let node = |p: PointId, r: [f64; 3]| Node {
            point: p,
            alpha: 0.01,
            beta: 0.0,
            gamma: 0.0,
            offset: [0.0; 3],
            reference: r,
            ring_shift: None,
        };
        Template {
            schema: SCHEMA_ID.into(),
            schema_version: SCHEMA_VERSION,
            vocabulary: VOCABULARY_VERSION,
            name: "tiny".into(),
            version: 1,
            description: String::new(),
            ease_mm: BTreeMap::new(),
            ease_range_mm: BTreeMap::new(),
            design_body: None,
            nodes: vec![
                node(PointId::WaistFront, [0.0, 0.0, 0.1]),
                node(PointId::WaistLeft, [0.1, 0.0, 0.0]),
                node(PointId::HipFront, [0.0, -0.2, 0.1]),
            ],
            edges: vec![
                Edge { start: 0, end: 1, profile: vec![] },
                Edge { start: 1, end: 2, profile: vec![] },
                Edge { start: 0, end: 2, profile: vec![] },
            ],
            faces: vec![Face { edges: [0, 1, 2], directions: [1, 1, -1] }],
            panels: vec![Panel {
                name: "front".into(),
                faces: vec![0],
                grain: GrainLine { from: 0, to: 2, stack: None },
                quantity: 1,
            }],
            seams: vec![],
            notches: vec![],
            darts: vec![],
            drops: vec![],
            on_curve: vec![],
            between: vec![],
            below: vec![],
            hangs: vec![],
            mirror_pairs: vec![],
            defaults: GradingDefaults::default(),
        }
    }

    #[test]
    fn tiny_round_trips_and_matches_the_schema() {
        let t = tiny();
        t.validate().unwrap();
        let back = Template::from_json(&t.to_json()).unwrap();
        assert_eq!(back, t);
        assert_eq!(t.face_nodes(0), [0, 1, 2]);
    }

    #[test]
    fn an_ease_range_and_a_design_body_round_trip_and_a_reversed_range_is_named() {
        let mut t = tiny();
        t.ease_range_mm.insert("hip".into(), [20.0, 60.0]);
        t.design_body = Some(DesignBody::MakehumanBase);
        let text = t.to_json();
        assert!(text.contains("\"design_body\": \"makehuman-base\""), "{text}");
        assert_eq!(Template::from_json(&text).unwrap(), t, "pass the schema and round-trip");
        t.ease_range_mm.insert("waist".into(), [30.0, 10.0]);
        match t.validate() {
            Err(TemplateError::BadReference { element, .. }) => assert_eq!(element, "ease range of `waist`"),
            other => panic!("{other:?}"),
        }
        // the schema refuses a range that is not a pair, and an unknown body
        let bad = tiny().to_json().replacen("\"ease_mm\": {}", "\"ease_mm\": {}, \"ease_range_mm\": {\"hip\": [1]}", 1);
        assert!(matches!(Template::from_json(&bad), Err(TemplateError::Schema(_))), "{bad}");
        let bad = tiny().to_json().replacen("\"ease_mm\": {}", "\"ease_mm\": {}, \"design_body\": \"moon\"", 1);
        assert!(matches!(Template::from_json(&bad), Err(TemplateError::Schema(_))));
        // a chart's size and a stored scan round-trip too; a scan without its id does not pass
        let row = crate::mannequin::size_chart::SizeRow {
            size: "38".into(),
            targets: [(crate::body::measure::MeasurementId::HipGirth, 1.0)].into(),
            alternatives: Default::default(),
        };
        for body in [
            DesignBody::ChartSize { sex: crate::mannequin::size_chart::Sex::Female, row },
            DesignBody::Scan { id: "b3f1".into() },
        ] {
            let t = Template { design_body: Some(body), ..tiny() };
            assert_eq!(Template::from_json(&t.to_json()).unwrap(), t);
        }
        let bad = tiny().to_json().replacen("\"ease_mm\": {}", "\"ease_mm\": {}, \"design_body\": {\"scan\": {}}", 1);
        assert!(matches!(Template::from_json(&bad), Err(TemplateError::Schema(_))), "{bad}");
    }

    #[test]
    fn unknown_feature_id_is_named() {
        let text = tiny().to_json().replace("\"waist_left\"", "\"waist_middle\"");
        let e = Template::from_json(&text).unwrap_err();
        assert!(e.to_string().contains("waist_middle"), "{e}");
    }

    #[test]
    fn face_naming_a_missing_edge() {
        let mut t = tiny();
        t.faces[0].edges[2] = 9;
        assert_eq!(t.validate(), Err(TemplateError::MissingEdge { face: 0, edge: 9 }));
    }

    #[test]
    fn inconsistent_edge_directions() {
        let mut t = tiny();
        t.faces[0].directions = [1, 1, 1];
        assert_eq!(t.validate(), Err(TemplateError::InconsistentDirections { face: 0 }));
    }

    #[test]
    fn non_manifold_edge() {
        let mut t = tiny();
        for _ in 0..2 {
            t.nodes.push(t.nodes[2].clone());
        }
        // two more triangles on edge 0 (nodes 0–1)
        t.edges.push(Edge { start: 1, end: 3, profile: vec![] }); // 3
        t.edges.push(Edge { start: 0, end: 3, profile: vec![] }); // 4
        t.edges.push(Edge { start: 1, end: 4, profile: vec![] }); // 5
        t.edges.push(Edge { start: 0, end: 4, profile: vec![] }); // 6
        t.faces.push(Face { edges: [0, 4, 3], directions: [-1, 1, -1] });
        t.faces.push(Face { edges: [0, 6, 5], directions: [-1, 1, -1] });
        t.panels[0].faces = vec![0, 1, 2];
        assert_eq!(t.validate(), Err(TemplateError::Topology(TopologyError::NonManifoldEdge { edge: 0, faces: 3 })));
    }

    #[test]
    fn same_direction_twice_is_inconsistent_orientation() {
        let mut t = tiny();
        t.nodes.push(t.nodes[2].clone());
        t.edges.push(Edge { start: 1, end: 3, profile: vec![] });
        t.edges.push(Edge { start: 0, end: 3, profile: vec![] });
        t.faces.push(Face { edges: [0, 3, 4], directions: [1, 1, -1] });
        t.panels[0].faces = vec![0, 1];
        assert_eq!(
            t.validate(),
            Err(TemplateError::Topology(TopologyError::InconsistentOrientation {
                edge: 0,
                face_a: FaceId(0),
                face_b: FaceId(1)
            }))
        );
    }

    #[test]
    fn non_finite_numbers() {
        let mut t = tiny();
        t.nodes[1].beta = f64::NAN;
        assert_eq!(t.validate(), Err(TemplateError::NonFinite { element: "node 1".into() }));
        let mut t = tiny();
        t.edges[0].profile = vec![[0.0, 0.0, 0.1], [0.05, f64::INFINITY, 0.05], [0.1, 0.0, 0.0]];
        assert_eq!(t.validate(), Err(TemplateError::NonFinite { element: "edge 0 profile".into() }));
        // JSON cannot carry NaN; an overflowing literal is refused at parse time
        let text = tiny().to_json().replace("\"alpha\": 0.01", "\"alpha\": 1e999");
        assert!(matches!(Template::from_json(&text), Err(TemplateError::Syntax(_))));
    }

    #[test]
    fn schema_version_from_the_future() {
        let text = tiny().to_json().replace("\"schema_version\": 1", "\"schema_version\": 7");
        assert_eq!(
            Template::from_json(&text),
            Err(TemplateError::FutureSchema { found: 7, supported: SCHEMA_VERSION })
        );
    }

    #[test]
    fn schema_catches_unknown_fields() {
        let text = tiny().to_json().replacen("\"name\": \"tiny\"", "\"name\": \"tiny\", \"colour\": \"red\"", 1);
        assert!(matches!(Template::from_json(&text), Err(TemplateError::Schema(_))));
    }

    #[test]
    fn dangling_panel_and_seam_references() {
        let mut t = tiny();
        t.seams.push(Seam { name: "s".into(), panel_a: "front".into(), panel_b: "back".into(), edges: vec![0] });
        assert!(matches!(t.validate(), Err(TemplateError::BadReference { .. })));
        let mut t = tiny();
        t.panels[0].faces.clear();
        assert!(matches!(t.validate(), Err(TemplateError::BadReference { .. })));
    }

    #[test]
    fn a_drop_round_trips_and_bad_ones_name_the_node() {
        let mut t = tiny();
        t.drops.push(Drop { node: 2, from: 0, girth: CurveId::Hip, length_m: 0.35, flare_m: 0.06 });
        t.validate().unwrap();
        assert_eq!(Template::from_json(&t.to_json()).unwrap(), t, "drops pass the schema and round-trip");
        for bad in [
            Drop { node: 7, from: 0, girth: CurveId::Hip, length_m: 0.35, flare_m: 0.0 },
            Drop { node: 1, from: 1, girth: CurveId::Hip, length_m: 0.35, flare_m: 0.0 },
            Drop { node: 1, from: 0, girth: CurveId::Hip, length_m: f64::NAN, flare_m: 0.0 },
        ] {
            let mut t = tiny();
            t.drops.push(bad);
            match t.validate() {
                Err(TemplateError::BadReference { element, .. }) => {
                    assert_eq!(element, format!("drop of node {}", bad.node));
                }
                other => panic!("{bad:?}: {other:?}"),
            }
        }
    }

    #[test]
    fn an_on_curve_placement_round_trips_and_bad_ones_name_the_node() {
        let place = |node: u32, from: PointId, fraction: f64| OnCurve {
            node,
            curve: CurveId::ArmscyeLeft,
            from,
            to: PointId::UnderarmLeft,
            via: PointId::ChestFront,
            fraction,
            radial_m: 0.006,
            normal_m: -0.004,
        };
        let mut t = tiny();
        t.on_curve.push(place(2, PointId::ShoulderLeft, 0.5));
        t.validate().unwrap();
        assert_eq!(Template::from_json(&t.to_json()).unwrap(), t, "placements pass the schema and round-trip");
        for bad in [
            place(7, PointId::ShoulderLeft, 0.5),
            place(1, PointId::ShoulderLeft, 1.5),
            place(1, PointId::ShoulderLeft, f64::NAN),
            place(1, PointId::UnderarmLeft, 0.5),
        ] {
            let mut t = tiny();
            t.on_curve.push(bad);
            match t.validate() {
                Err(TemplateError::BadReference { element, .. }) => {
                    assert_eq!(element, format!("on-curve placement of node {}", bad.node));
                }
                other => panic!("{bad:?}: {other:?}"),
            }
        }
        // a fraction outside [0, 1] is refused by the schema too
        let mut doc: serde_json::Value = serde_json::from_str(&t.to_json()).unwrap();
        doc["on_curve"] = serde_json::json!([{"node": 1, "curve": "armscye_left", "from": "shoulder_left",
            "to": "underarm_left", "via": "chest_front", "fraction": 2.0, "radial_m": 0.0}]);
        assert!(matches!(Template::from_json(&doc.to_string()), Err(TemplateError::Schema(_))));
    }
}
