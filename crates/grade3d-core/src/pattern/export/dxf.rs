//! DXF export of pattern pieces in the AAMA / ASTM D6673-10 style, the
//! pattern interchange that pattern CAD systems (Gerber AccuMark, Lectra,
//! Optitex, CLO, Valentina/Seamly2D, …) import.
//!
//! # Contract
//!
//! - **Profiles** ([`DxfProfile`], issue #14 item 6): [`DxfProfile::Aama`]
//!   (default) writes the file described below; [`DxfProfile::GerberAccuMark`]
//!   writes the strict R12 form Gerber AccuMark's parser wants (as ezdxf's
//!   `gerber_D6673` add-on documents it): an *empty* HEADER section, *no*
//!   TABLES section, no text style named on TEXT (R12's default STANDARD),
//!   7-bit ASCII, and otherwise the same BLOCKS and ENTITIES.
//! - **Format**: an ASCII DXF, AutoCAD Release 12 (`$ACADVER` = `AC1009`), CR
//!   LF line ends, no handles (as the AAMA files pattern systems write):
//!   HEADER (`$ACADVER`, `$INSBASE`, `$EXTMIN`, `$EXTMAX`, `$CLAYER`), TABLES
//!   (`LTYPE` CONTINUOUS, `LAYER` 0 and the AAMA layers, `STYLE` STANDARD),
//!   BLOCKS, ENTITIES. Strings are 7-bit: other characters (and `\`) are
//!   written as `\U+XXXX`, control characters in caret notation (`^J`), a
//!   caret as `^ `; characters beyond U+FFFF as `?`; a string is cut at 255
//!   characters (the R12 limit).
//! - **Why not the `dxf` crate for writing**: `dxf` 0.6.2 writes subclass
//!   markers (group 100, `AcDbSymbolTable…`, `AcDbVertex`) in TABLES and on
//!   VERTEX even for R12, where they do not exist; ezdxf refuses such a file
//!   (`DXFTypeError` on the first table entry). The file is therefore written
//!   here, group by group; [`read_outlines`] reads it back with `dxf`.
//! - **Units and axes**: millimetres, x to the right, y up, as the pieces.
//!   R12 has no units header variable (`$INSUNITS` is R2000+, `$MEASUREMENT`
//!   R14+), so the units are stated the AAMA way, by the style system text
//!   `Units: METRIC` (metric AAMA files are in millimetres).
//! - **Style system text** (ENTITIES, layer `1`, above the pieces, once per
//!   file): `Style Name: …`, `Author: …`, `PRODUCT: …`, `VERSION: …`, with a
//!   rule table `Sample Size: …` and `Grade Rule Table: …`, then
//!   `Units: METRIC`. No creation date or time (determinism).
//! - **One BLOCK per piece** (per piece and size in a graded nest), its base
//!   point the piece's origin (stack point); block names are the piece name
//!   (`NAME_SIZE` in a nest) upper-cased, reduced to `A–Z 0–9 _ -`, at most
//!   31 characters and unique (`_2`, `_3`, … suffixes). Each block is
//!   inserted once in ENTITIES (layer `1`): pieces side by side without
//!   overlap ([`ShelfLayout`]), rows growing downwards from y = 0; in a nest
//!   all sizes of a piece are inserted at the same point (stacked).
//! - **Layers inside a block** (AAMA numbering):
//!   - `1` boundary: the cut line as a closed `POLYLINE`, and the piece
//!     system text `Piece Name: …`, `Size: …`, `Quantity: …` (and
//!     `Annotation: cut pair (one mirrored)` for a mirror pair cut as one);
//!   - `2` turn points / `3` curve points: a `POINT` at every vertex of the
//!     boundary, the sew line and the internal lines — turn points at the
//!     corners (`PatternPiece::corners`; a boundary vertex takes the kind of
//!     the sew-line vertex it was offset from) and at the ends of internal
//!     lines, curve points elsewhere;
//!   - `4` notches: a `POINT` on the boundary where the notch is cut, its
//!     angle (group 50, degrees counter-clockwise from +x) pointing into the
//!     piece, towards the notch's sew-line point — the slit notch of the
//!     AAMA/ASTM files Gerber AccuMark and CLO write. [`NotchEntity::Line`]
//!     writes a `LINE` from the boundary inwards instead, for importers that
//!     read notches as lines;
//!   - `7` grain line: a `LINE` from the grain line's start to its end;
//!   - `8` internal lines: an open `POLYLINE` each;
//!   - `14` sew line: the sew line as a closed `POLYLINE`.
//! - **Grade rules** (the `*_with_rules` functions): the AAMA way of naming
//!   a grade point's rule is a `TEXT` `# n` at the point, on the layer of
//!   the point (2 or 3); in a nest only on the sample size's pieces (the
//!   table's base size), as graded nests carry them. Every sew-line vertex carrying a grade point gets
//!   its rule number, and so does the boundary vertex offset from it; rules
//!   are matched to grade points by template node. The numbers refer to the
//!   `.RUL` file of the same table ([`super::rul`]).
//! - **Precision**: coordinates are written with [`DxfOptions::decimals`]
//!   decimals (default 6, i.e. 1 nm), so a read-back is within 10⁻⁶ mm.
//! - **Determinism**: the same input and options give the same bytes (no
//!   dates, no handles, everything in input order).
//!
//! # Failure modes
//!
//! [`ExportError::DegenerateOutline`] for a cut line with fewer than three
//! points, [`ExportError::NonFinite`] for any coordinate that is NaN or
//! infinite, [`ExportError::BadOption`] for unusable options, and
//! [`ExportError::Dxf`] when the `dxf` crate cannot read a file
//! ([`read_outlines`]).

use std::collections::BTreeSet;
use std::fmt::Write as _;

use dxf::entities::EntityType;
use dxf::Drawing;
use glam::DVec2;

use super::{fmt_num, piece_bounds, Bounds, ExportError, NotchMark, ShelfLayout};
use crate::pattern::piece::{GradePointKind, GradeRuleTable, PatternPiece};

/// AAMA layer of the boundary (cut line) and the system text.
pub const LAYER_BOUNDARY: &str = "1";
/// AAMA layer of turn points.
pub const LAYER_TURN_POINTS: &str = "2";
/// AAMA layer of curve points.
pub const LAYER_CURVE_POINTS: &str = "3";
/// AAMA layer of notches.
pub const LAYER_NOTCHES: &str = "4";
/// AAMA layer of the grain line.
pub const LAYER_GRAIN: &str = "7";
/// AAMA layer of internal lines.
pub const LAYER_INTERNAL: &str = "8";
/// AAMA layer of sew lines.
pub const LAYER_SEW: &str = "14";

/// The layers of the LAYER table: DXF's default layer 0 and the AAMA layers written.
const LAYERS: [&str; 8] =
    ["0", LAYER_BOUNDARY, LAYER_TURN_POINTS, LAYER_CURVE_POINTS, LAYER_NOTCHES, LAYER_GRAIN, LAYER_INTERNAL, LAYER_SEW];

/// AutoCAD colour index of every layer: 7, black on white (white on black).
const LAYER_COLOUR: i32 = 7;

/// Longest block name R12 accepts (characters).
const MAX_BLOCK_NAME: usize = 31;

/// Longest string value R12 accepts (characters).
const MAX_STRING: usize = 255;

/// Block-type flag of the AAMA files pattern systems write: 64, "referenced".
const BLOCK_FLAG_REFERENCED: i32 = 64;

/// A grade point lies on a sew-line vertex when closer than this fraction
/// of the piece's extent (grade points are copies of vertices, so this only
/// absorbs rounding).
const SAME_POINT_RELATIVE: f64 = 1e-9;

/// POLYLINE flag: closed.
const POLYLINE_CLOSED: i32 = 1;

/// Which DXF entity a notch is written as (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum NotchEntity {
    /// A `POINT` on the boundary with the notch's angle (AAMA/ASTM as
    /// written by Gerber AccuMark and CLO).
    #[default]
    Point,
    /// A `LINE` from the boundary [`DxfOptions::notch_depth_mm`] into the
    /// piece (at most to the sew line).
    Line,
}

/// Which importer's form of the file to write (module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DxfProfile {
    /// The AAMA / ASTM D6673 form with HEADER variables and TABLES (CLO,
    /// Lectra, Optitex, Valentina, ezdxf).
    #[default]
    Aama,
    /// Gerber AccuMark's strict R12 form: empty HEADER, no TABLES.
    GerberAccuMark,
}

/// How the DXF is written. Lengths are millimetres.
#[derive(Debug, Clone, PartialEq)]
pub struct DxfOptions {
    /// The importer's form of the file. Default [`DxfProfile::Aama`].
    pub profile: DxfProfile,
    /// Placement of the pieces side by side. Default [`ShelfLayout::default`] (20 mm gap, 1600 mm rows).
    pub layout: ShelfLayout,
    /// Height of the style and piece system text, mm. Default 5 mm.
    pub text_height_mm: f64,
    /// Distance between lines of system text, as a multiple of the text height. Default 1.5.
    pub line_spacing: f64,
    /// Height of the grade rule numbers (`# n`), mm. Default 2.5 mm.
    pub rule_text_height_mm: f64,
    /// Entity that notches are written as. Default [`NotchEntity::Point`].
    pub notch: NotchEntity,
    /// Length of a notch written as a line ([`NotchEntity::Line`]), mm, at
    /// most up to the sew line. Default 6 mm.
    pub notch_depth_mm: f64,
    /// Decimals of the coordinates written (count, 0 to 12). Default 6 (nm).
    pub decimals: usize,
    /// Style system text `Author:`. Default `grade3d`.
    pub author: String,
    /// Style system text `PRODUCT:`. Default `grade3d`.
    pub product: String,
    /// Style system text `VERSION:`. Default: this crate's version.
    pub version: String,
}

impl Default for DxfOptions {
    fn default() -> Self {
        Self {
            profile: DxfProfile::Aama,
            layout: ShelfLayout::default(),
            text_height_mm: 5.0,
            line_spacing: 1.5,
            rule_text_height_mm: 2.5,
            notch: NotchEntity::Point,
            notch_depth_mm: 6.0,
            decimals: 6,
            author: "grade3d".to_string(),
            product: "grade3d".to_string(),
            version: env!("CARGO_PKG_VERSION").to_string(),
        }
    }
}

/// The pieces (typically all pieces of one size) side by side, one block
/// each, as an AAMA-style R12 DXF (module docs).
///
/// # Errors
/// [`ExportError::DegenerateOutline`], [`ExportError::NonFinite`],
/// [`ExportError::BadOption`].
pub fn pieces_dxf(style: &str, pieces: &[PatternPiece], opts: &DxfOptions) -> Result<Vec<u8>, ExportError> {
    let groups: Vec<Vec<&PatternPiece>> = pieces.iter().map(|p| vec![p]).collect();
    write(style, &groups, false, None, opts)
}

/// [`pieces_dxf`] with the grade rule numbers of `rules` at the grade points
/// and the table's sample size in the style text.
///
/// # Errors
/// As [`pieces_dxf`].
pub fn pieces_dxf_with_rules(
    style: &str,
    pieces: &[PatternPiece],
    rules: &GradeRuleTable,
    opts: &DxfOptions,
) -> Result<Vec<u8>, ExportError> {
    let groups: Vec<Vec<&PatternPiece>> = pieces.iter().map(|p| vec![p]).collect();
    write(style, &groups, false, Some(rules), opts)
}

/// The graded nest as an AAMA-style R12 DXF: one block per piece and size,
/// all sizes of a piece inserted at the same point, pieces side by side
/// (module docs). `nests` is `(piece name, its pieces smallest to largest)`.
///
/// # Errors
/// As [`pieces_dxf`].
pub fn nest_dxf(style: &str, nests: &[(String, Vec<PatternPiece>)], opts: &DxfOptions) -> Result<Vec<u8>, ExportError> {
    let groups: Vec<Vec<&PatternPiece>> = nests.iter().map(|(_, graded)| graded.iter().collect()).collect();
    write(style, &groups, true, None, opts)
}

/// [`nest_dxf`] with the grade rule numbers of `rules` at the grade points
/// of every size and the table's sample size in the style text.
///
/// # Errors
/// As [`pieces_dxf`].
pub fn nest_dxf_with_rules(
    style: &str,
    nests: &[(String, Vec<PatternPiece>)],
    rules: &GradeRuleTable,
    opts: &DxfOptions,
) -> Result<Vec<u8>, ExportError> {
    let groups: Vec<Vec<&PatternPiece>> = nests.iter().map(|(_, graded)| graded.iter().collect()).collect();
    write(style, &groups, true, Some(rules), opts)
}

/// Reads a DXF back with the `dxf` crate and returns, for every block that
/// has a boundary (a `POLYLINE` on layer `1`), its piece name (the
/// `Piece Name:` text, else the block name) and the boundary's vertices, in
/// block order. A closing vertex that repeats the first one is dropped.
///
/// # Errors
/// [`ExportError::Dxf`] when the bytes are not a DXF the crate reads.
pub fn read_outlines(bytes: &[u8]) -> Result<Vec<(String, Vec<DVec2>)>, ExportError> {
    let drawing = Drawing::load(&mut &bytes[..]).map_err(|e| ExportError::Dxf(e.to_string()))?;
    let mut out = Vec::new();
    for block in drawing.blocks() {
        let mut name = None;
        let mut outline = None;
        for e in &block.entities {
            if e.common.layer != LAYER_BOUNDARY {
                continue;
            }
            match &e.specific {
                EntityType::Text(t) => {
                    if let Some(rest) = strip_prefix_ignore_case(&t.value, PIECE_NAME) {
                        name.get_or_insert_with(|| rest.trim().to_string());
                    }
                }
                EntityType::Polyline(p) if outline.is_none() => {
                    let mut pts: Vec<DVec2> = p.vertices().map(|v| DVec2::new(v.location.x, v.location.y)).collect();
                    if pts.len() > 1 && pts.first() == pts.last() {
                        pts.pop();
                    }
                    outline = Some(pts);
                }
                _ => {}
            }
        }
        if let Some(outline) = outline {
            out.push((name.unwrap_or_else(|| block.name.clone()), outline));
        }
    }
    Ok(out)
}

/// Piece system text key of the piece name.
const PIECE_NAME: &str = "Piece Name:";
/// The annotation of a piece that stands for a mirror pair
/// ([`PatternPiece::cut_pair`]): cut one right side up and one mirrored.
pub const CUT_PAIR: &str = "Annotation: cut pair (one mirrored)";

/// `s` without `prefix` (ASCII case-insensitive), if it starts with it.
fn strip_prefix_ignore_case<'a>(s: &'a str, prefix: &str) -> Option<&'a str> {
    let head = s.get(..prefix.len())?;
    head.eq_ignore_ascii_case(prefix).then(|| &s[prefix.len()..])
}

/// Writes the drawing: `groups` are the blocks inserted at one point (one
/// piece, or all sizes of one piece); `nested` names blocks `NAME_SIZE`.
fn write(
    style: &str,
    groups: &[Vec<&PatternPiece>],
    nested: bool,
    rules: Option<&GradeRuleTable>,
    opts: &DxfOptions,
) -> Result<Vec<u8>, ExportError> {
    check_options(opts)?;
    for p in groups.iter().flatten() {
        check_piece(p)?;
    }
    let boxes: Vec<Option<Bounds>> =
        groups.iter().map(|g| g.iter().map(|p| piece_bounds(p)).fold(None, Bounds::union_opt)).collect();
    let shifts = opts.layout.place(&boxes);

    // style system text, above the first row
    let mut style_text = vec![
        format!("Style Name: {style}"),
        format!("Author: {}", opts.author),
        format!("PRODUCT: {}", opts.product),
        format!("VERSION: {}", opts.version),
    ];
    if let Some(r) = rules {
        style_text.push(format!("Sample Size: {}", r.base_size));
        style_text.push(format!("Grade Rule Table: {}", r.style));
    }
    style_text.push("Units: METRIC".to_string());
    let pitch = opts.text_height_mm * opts.line_spacing;
    let top = opts.layout.gap_mm.max(0.0) + pitch * style_text.len() as f64;
    let style_at = |i: usize| DVec2::new(0.0, top - pitch * (i + 1) as f64);

    let placed = boxes.iter().zip(&shifts).map(|(b, t)| b.map(|b| b.translated(*t))).fold(None, Bounds::union_opt);
    let text_box = Bounds::of([DVec2::new(0.0, top), style_at(style_text.len().saturating_sub(1))]);
    let extents = Bounds::union_opt(placed, text_box).unwrap_or(Bounds { min: DVec2::ZERO, max: DVec2::ZERO });

    let gerber = opts.profile == DxfProfile::GerberAccuMark;
    let mut w = Writer { out: String::new(), decimals: opts.decimals, text_style: !gerber };
    if gerber {
        w.section("HEADER");
        w.end_section();
    } else {
        w.header(extents);
        w.tables(opts.text_height_mm);
    }

    // blocks, and where each is inserted
    w.section("BLOCKS");
    let mut used = BTreeSet::new();
    let mut inserts = Vec::new();
    for (group, &shift) in groups.iter().zip(&shifts) {
        for piece in group {
            let raw = if nested { format!("{}_{}", piece.name, piece.size) } else { piece.name.clone() };
            let name = block_name(&mut used, &raw);
            // a nest numbers its grade points on the sample size only
            let numbered = rules.filter(|r| !nested || piece.size == r.base_size);
            w.block(&name, |w| piece_entities(w, piece, numbered, opts));
            inserts.push((name, shift));
        }
    }
    w.end_section();

    w.section("ENTITIES");
    for (i, line) in style_text.iter().enumerate() {
        w.text(LAYER_BOUNDARY, style_at(i), opts.text_height_mm, line);
    }
    for (name, at) in &inserts {
        w.insert(LAYER_BOUNDARY, name, *at);
    }
    w.end_section();
    w.pair(0, "EOF");
    Ok(w.out.into_bytes())
}

/// Rejects options the writer cannot use.
fn check_options(o: &DxfOptions) -> Result<(), ExportError> {
    let positive = |option: &'static str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(ExportError::BadOption { option, value: v.to_string(), expected: "a finite number > 0" })
        }
    };
    positive("text_height_mm", o.text_height_mm)?;
    positive("line_spacing", o.line_spacing)?;
    positive("rule_text_height_mm", o.rule_text_height_mm)?;
    positive("notch_depth_mm", o.notch_depth_mm)?;
    if !(o.layout.gap_mm.is_finite() && o.layout.max_row_width_mm.is_finite()) {
        return Err(ExportError::BadOption {
            option: "layout",
            value: format!("{:?}", o.layout),
            expected: "finite gap and row width",
        });
    }
    if o.decimals > 12 {
        return Err(ExportError::BadOption { option: "decimals", value: o.decimals.to_string(), expected: "0 to 12" });
    }
    Ok(())
}

/// Rejects a piece with a degenerate cut line or non-finite coordinates.
fn check_piece(p: &PatternPiece) -> Result<(), ExportError> {
    let bad = |what: &'static str| ExportError::NonFinite { piece: p.name.clone(), size: p.size.clone(), what };
    if p.cut_line.len() < 3 {
        return Err(ExportError::DegenerateOutline {
            piece: p.name.clone(),
            size: p.size.clone(),
            points: p.cut_line.len(),
        });
    }
    let finite = |pts: &[DVec2]| pts.iter().all(|q| q.is_finite());
    if !finite(&p.cut_line) {
        return Err(bad("cut line"));
    }
    if !finite(&p.sew_line) {
        return Err(bad("sew line"));
    }
    if !p.notches.iter().all(|n| n.at.is_finite() && n.on_cut_line.is_finite() && n.outward.is_finite()) {
        return Err(bad("notch"));
    }
    if !finite(&p.grain) {
        return Err(bad("grain line"));
    }
    if !p.internal_lines.iter().all(|l| finite(&l.points)) {
        return Err(bad("internal line"));
    }
    if !p.grade_points.iter().all(|g| g.at.is_finite()) {
        return Err(bad("grade point"));
    }
    Ok(())
}

/// A legal, unique R12 block name for `raw` (module docs); records it.
fn block_name(used: &mut BTreeSet<String>, raw: &str) -> String {
    let mut base: String = raw
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '-' || c == '_' { c.to_ascii_uppercase() } else { '_' })
        .take(MAX_BLOCK_NAME)
        .collect();
    if base.is_empty() {
        base = "PIECE".to_string();
    }
    let mut name = base.clone();
    let mut k = 2;
    while used.contains(&name) {
        let suffix = format!("_{k}");
        let keep = MAX_BLOCK_NAME.saturating_sub(suffix.len()).min(base.len());
        name = format!("{}{suffix}", &base[..keep]);
        k += 1;
    }
    used.insert(name.clone());
    name
}

/// A string value as R12 writes it (module docs): 7-bit, escaped, at most
/// [`MAX_STRING`] characters (an escape is never cut).
fn dxf_string(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        let code = c as u32;
        let piece = match c {
            '^' => "^ ".to_string(),
            '\\' | '\u{7f}' => format!("\\U+{code:04X}"),
            _ if code < 0x20 => format!("^{}", char::from_u32(code + 0x40).unwrap_or('?')),
            c if c.is_ascii() => c.to_string(),
            _ if code <= 0xFFFF => format!("\\U+{code:04X}"),
            _ => "?".to_string(),
        };
        if out.len() + piece.len() > MAX_STRING {
            break;
        }
        out.push_str(&piece);
    }
    out
}

/// Writes the group codes of an R12 DXF.
struct Writer {
    out: String,
    decimals: usize,
    /// Name the STANDARD text style on TEXT (not where there is no STYLE table).
    text_style: bool,
}

impl Writer {
    /// One group: code right-aligned in three columns, then the value.
    fn pair(&mut self, code: u16, value: &str) {
        let _ = write!(self.out, "{code:>3}\r\n{value}\r\n");
    }

    /// An integer group (right-aligned in six columns, as AutoCAD writes).
    fn int(&mut self, code: u16, v: i32) {
        self.pair(code, &format!("{v:>6}"));
    }

    /// A real group, with a decimal point.
    fn real(&mut self, code: u16, v: f64) {
        let mut s = fmt_num(v, self.decimals);
        if !s.contains('.') {
            s.push_str(".0");
        }
        self.pair(code, &s);
    }

    /// A string group (escaped).
    fn string(&mut self, code: u16, s: &str) {
        self.pair(code, &dxf_string(s));
    }

    /// A point: `code`, `code + 10`, `code + 20` (z = 0).
    fn xyz(&mut self, code: u16, p: DVec2) {
        self.real(code, p.x);
        self.real(code + 10, p.y);
        self.real(code + 20, 0.0);
    }

    fn section(&mut self, name: &str) {
        self.pair(0, "SECTION");
        self.pair(2, name);
    }

    fn end_section(&mut self) {
        self.pair(0, "ENDSEC");
    }

    fn header(&mut self, extents: Bounds) {
        self.section("HEADER");
        self.pair(9, "$ACADVER");
        self.pair(1, "AC1009");
        self.pair(9, "$INSBASE");
        self.xyz(10, DVec2::ZERO);
        self.pair(9, "$EXTMIN");
        self.xyz(10, extents.min);
        self.pair(9, "$EXTMAX");
        self.xyz(10, extents.max);
        self.pair(9, "$CLAYER");
        self.pair(8, LAYER_BOUNDARY);
        self.end_section();
    }

    fn tables(&mut self, text_height: f64) {
        self.section("TABLES");
        self.pair(0, "TABLE");
        self.pair(2, "LTYPE");
        self.int(70, 1);
        self.pair(0, "LTYPE");
        self.pair(2, "CONTINUOUS");
        self.int(70, 0);
        self.pair(3, "Solid line");
        self.int(72, i32::from(b'A'));
        self.int(73, 0);
        self.real(40, 0.0);
        self.pair(0, "ENDTAB");

        self.pair(0, "TABLE");
        self.pair(2, "LAYER");
        self.int(70, LAYERS.len() as i32);
        for name in LAYERS {
            self.pair(0, "LAYER");
            self.pair(2, name);
            self.int(70, 0);
            self.int(62, LAYER_COLOUR);
            self.pair(6, "CONTINUOUS");
        }
        self.pair(0, "ENDTAB");

        self.pair(0, "TABLE");
        self.pair(2, "STYLE");
        self.int(70, 1);
        self.pair(0, "STYLE");
        self.pair(2, "STANDARD");
        self.int(70, 0);
        self.real(40, 0.0);
        self.real(41, 1.0);
        self.real(50, 0.0);
        self.int(71, 0);
        self.real(42, text_height);
        self.pair(3, "txt");
        self.pair(4, "");
        self.pair(0, "ENDTAB");
        self.end_section();
    }

    /// A block with base point at the origin; `body` writes its entities.
    fn block(&mut self, name: &str, body: impl FnOnce(&mut Self)) {
        self.pair(0, "BLOCK");
        self.pair(8, "0");
        self.pair(2, name);
        self.int(70, BLOCK_FLAG_REFERENCED);
        self.xyz(10, DVec2::ZERO);
        self.pair(3, name);
        body(self);
        self.pair(0, "ENDBLK");
        self.pair(8, "0");
    }

    /// A left-aligned `TEXT` in the STANDARD style.
    fn text(&mut self, layer: &str, at: DVec2, height: f64, value: &str) {
        self.pair(0, "TEXT");
        self.pair(8, layer);
        self.xyz(10, at);
        self.real(40, height);
        self.string(1, value);
        if self.text_style {
            self.pair(7, "STANDARD");
        }
    }

    /// A `POINT`, with an angle (degrees) for notches.
    fn point(&mut self, layer: &str, at: DVec2, angle: Option<f64>) {
        self.pair(0, "POINT");
        self.pair(8, layer);
        self.xyz(10, at);
        if let Some(a) = angle {
            self.real(50, a);
        }
    }

    fn line(&mut self, layer: &str, a: DVec2, b: DVec2) {
        self.pair(0, "LINE");
        self.pair(8, layer);
        self.xyz(10, a);
        self.xyz(11, b);
    }

    /// A 2D `POLYLINE` with its `VERTEX`es and `SEQEND`, all on `layer`.
    fn polyline(&mut self, layer: &str, pts: &[DVec2], closed: bool) {
        self.pair(0, "POLYLINE");
        self.pair(8, layer);
        self.int(66, 1);
        self.xyz(10, DVec2::ZERO);
        self.int(70, if closed { POLYLINE_CLOSED } else { 0 });
        for &p in pts {
            self.pair(0, "VERTEX");
            self.pair(8, layer);
            self.xyz(10, p);
            self.int(70, 0);
        }
        self.pair(0, "SEQEND");
        self.pair(8, layer);
    }

    fn insert(&mut self, layer: &str, block: &str, at: DVec2) {
        self.pair(0, "INSERT");
        self.pair(8, layer);
        self.pair(2, block);
        self.xyz(10, at);
    }
}

/// The layer of a point: turn point or curve point.
fn point_layer(turn: bool) -> &'static str {
    if turn {
        LAYER_TURN_POINTS
    } else {
        LAYER_CURVE_POINTS
    }
}

/// The rule number of every sew-line vertex that carries a grade point (the
/// first grade point there), and the grade points off the sew line's
/// vertices (position, rule, corner?), from the piece's rules in `table`.
type VertexRules = (Vec<Option<u32>>, Vec<(DVec2, u32, bool)>);

fn sew_vertex_rules(p: &PatternPiece, table: Option<&GradeRuleTable>) -> VertexRules {
    let mut at_vertex = vec![None; p.sew_line.len()];
    let mut loose = Vec::new();
    let Some(rules) = table.and_then(|t| t.pieces.iter().find(|r| r.piece == p.name)) else {
        return (at_vertex, loose);
    };
    let scale = p.sew_line.iter().map(|q| q.abs().max_element()).fold(1.0, f64::max);
    let tol = scale * SAME_POINT_RELATIVE;
    for (j, g) in p.grade_points.iter().enumerate() {
        let rule =
            rules.rules.get(j).filter(|r| r.node == g.node).or_else(|| rules.rules.iter().find(|r| r.node == g.node));
        let Some(rule) = rule else { continue };
        match p.sew_line.iter().position(|q| q.distance(g.at) <= tol) {
            Some(k) => {
                at_vertex[k].get_or_insert(rule.number);
            }
            None => loose.push((g.at, rule.number, g.kind == GradePointKind::Corner)),
        }
    }
    (at_vertex, loose)
}

/// For every cut-line vertex, the sew-line vertex it was offset from: the
/// same index when both have as many vertices, else the nearest.
fn cut_to_sew(p: &PatternPiece) -> Vec<Option<usize>> {
    if p.cut_line.len() == p.sew_line.len() {
        return (0..p.cut_line.len()).map(Some).collect();
    }
    p.cut_line
        .iter()
        .map(|c| {
            p.sew_line
                .iter()
                .enumerate()
                .min_by(|a, b| a.1.distance_squared(*c).total_cmp(&b.1.distance_squared(*c)))
                .map(|(k, _)| k)
        })
        .collect()
}

/// Everything inside a piece's block (module docs).
fn piece_entities(w: &mut Writer, p: &PatternPiece, rules: Option<&GradeRuleTable>, o: &DxfOptions) {
    let corners: BTreeSet<usize> = p.corners.iter().copied().collect();
    let (sew_rules, loose_rules) = sew_vertex_rules(p, rules);
    let rule_text = |w: &mut Writer, layer: &str, at: DVec2, n: u32| {
        w.text(layer, at, o.rule_text_height_mm, &format!("# {n}"));
    };

    // piece system text, centred on the boundary's box
    let pitch = o.text_height_mm * o.line_spacing;
    let centre = Bounds::of(p.cut_line.iter().copied()).map_or(DVec2::ZERO, Bounds::centre);
    let mut lines =
        vec![format!("{PIECE_NAME} {}", p.name), format!("Size: {}", p.size), format!("Quantity: {}", p.quantity)];
    if p.cut_pair {
        lines.push(CUT_PAIR.to_owned());
    }
    for (i, line) in lines.iter().enumerate() {
        w.text(LAYER_BOUNDARY, centre + DVec2::new(0.0, pitch * (1.0 - i as f64)), o.text_height_mm, line);
    }

    // boundary, its turn and curve points
    w.polyline(LAYER_BOUNDARY, &p.cut_line, true);
    for (&c, k) in p.cut_line.iter().zip(cut_to_sew(p)) {
        let layer = point_layer(k.is_some_and(|k| corners.contains(&k)));
        w.point(layer, c, None);
        if let Some(n) = k.and_then(|k| sew_rules.get(k).copied().flatten()) {
            rule_text(w, layer, c, n);
        }
    }

    // sew line, its turn and curve points
    if p.sew_line.len() >= 2 {
        w.polyline(LAYER_SEW, &p.sew_line, true);
        for (k, &s) in p.sew_line.iter().enumerate() {
            let layer = point_layer(corners.contains(&k));
            w.point(layer, s, None);
            if let Some(n) = sew_rules[k] {
                rule_text(w, layer, s, n);
            }
        }
    }
    for &(at, n, corner) in &loose_rules {
        rule_text(w, point_layer(corner), at, n);
    }

    // notches
    for mark in p.notches.iter().filter_map(|n| NotchMark::of(n, &p.cut_line)) {
        match o.notch {
            NotchEntity::Point => {
                let angle = mark.inward.y.atan2(mark.inward.x).to_degrees().rem_euclid(360.0);
                w.point(LAYER_NOTCHES, mark.start, Some(angle));
            }
            NotchEntity::Line => w.line(LAYER_NOTCHES, mark.start, mark.end(o.notch_depth_mm)),
        }
    }

    // grain line
    w.line(LAYER_GRAIN, p.grain[0], p.grain[1]);

    // internal lines with their end (turn) and inner (curve) points
    for l in p.internal_lines.iter().filter(|l| l.points.len() >= 2) {
        w.polyline(LAYER_INTERNAL, &l.points, false);
        let last = l.points.len() - 1;
        for (i, &q) in l.points.iter().enumerate() {
            w.point(point_layer(i == 0 || i == last), q, None);
        }
    }
}

#[cfg(test)]
mod tests {
    use dxf::entities::{Insert, ModelPoint};
    use dxf::Block;

    use super::*;
    use crate::pattern::export::samples;

    fn ok<T>(r: Result<T, ExportError>) -> T {
        match r {
            Ok(v) => v,
            Err(e) => panic!("export failed: {e}"),
        }
    }

    fn max_error(a: &[DVec2], b: &[DVec2]) -> f64 {
        assert_eq!(a.len(), b.len());
        a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0, f64::max)
    }

    #[test]
    fn pieces_round_trip_through_read_outlines() {
        let pieces = samples::pieces("M", 0.0);
        let bytes = ok(pieces_dxf("Dress & co", &pieces, &DxfOptions::default()));
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.contains("AC1009"), "R12");
        assert!(text.contains("Units: METRIC"));
        assert!(text.contains("Style Name: Dress & co"));
        let outlines = ok(read_outlines(&bytes));
        assert_eq!(outlines.len(), pieces.len());
        for ((name, outline), p) in outlines.iter().zip(&pieces) {
            assert_eq!(name, &p.name);
            let e = max_error(outline, &p.cut_line);
            assert!(e < 1e-3, "{name}: {e} mm");
        }
    }

    #[test]
    fn the_gerber_profile_has_an_empty_header_and_no_tables() {
        let nests = samples::nests();
        let gerber = DxfOptions { profile: DxfProfile::GerberAccuMark, ..DxfOptions::default() };
        let bytes = ok(nest_dxf_with_rules("Dress", &nests, &samples::rules(), &gerber));
        let text = String::from_utf8(bytes.clone()).expect("ASCII");
        assert!(text.is_ascii());
        assert!(!text.contains("TABLES") && !text.contains("$ACADVER"), "no TABLES, empty HEADER");
        assert!(text.starts_with("  0\r\nSECTION\r\n  2\r\nHEADER\r\n  0\r\nENDSEC\r\n"), "{}", &text[..80]);
        // the same pieces as the AAMA profile, read back
        let aama = ok(nest_dxf_with_rules("Dress", &nests, &samples::rules(), &DxfOptions::default()));
        assert_eq!(ok(read_outlines(&bytes)), ok(read_outlines(&aama)));
    }

    #[test]
    fn nest_has_a_block_per_size_stacked() {
        let nests = samples::nests();
        let bytes = ok(nest_dxf_with_rules("Dress", &nests, &samples::rules(), &DxfOptions::default()));
        let drawing = ok(Drawing::load(&mut &bytes[..]).map_err(|e| ExportError::Dxf(e.to_string())));
        let blocks: Vec<&Block> = drawing.blocks().filter(|b| !b.name.starts_with('*')).collect();
        assert_eq!(blocks.len(), 9);
        let names: Vec<&str> = blocks.iter().map(|b| b.name.as_str()).collect();
        assert_eq!(&names[..3], ["FRONT____SIDE__S", "FRONT____SIDE__M", "FRONT____SIDE__L___XL"]);
        let inserts: Vec<&Insert> = drawing
            .entities()
            .filter_map(|e| if let EntityType::Insert(i) = &e.specific { Some(i) } else { None })
            .collect();
        assert_eq!(inserts.len(), 9);
        for group in inserts.chunks(3) {
            assert!(group.iter().all(|i| i.location == group[0].location), "sizes stacked");
        }
        assert_ne!(inserts[0].location, inserts[3].location);
        // sizes are there, and rule numbers on the sample size (M) only
        let texts = |b: &Block| -> Vec<String> {
            b.entities
                .iter()
                .filter_map(|e| if let EntityType::Text(t) = &e.specific { Some(t.value.clone()) } else { None })
                .collect()
        };
        let (sample, other) = (texts(blocks[1]), texts(blocks[2]));
        assert!(other.contains(&"Size: L & XL".to_string()), "{other:?}");
        assert!(sample.iter().filter(|t| t.starts_with("# ")).count() >= 5, "{sample:?}");
        assert!(!other.iter().any(|t| t.starts_with("# ")), "{other:?}");
        let style: Vec<String> = drawing
            .entities()
            .filter_map(|e| if let EntityType::Text(t) = &e.specific { Some(t.value.clone()) } else { None })
            .collect();
        assert!(style.contains(&"Sample Size: M".to_string()), "{style:?}");
        // the boundaries of every size read back
        let outlines = ok(read_outlines(&bytes));
        let expected: Vec<&PatternPiece> = nests.iter().flat_map(|(_, g)| g).collect();
        assert_eq!(outlines.len(), expected.len());
        for ((name, outline), p) in outlines.iter().zip(expected) {
            assert_eq!(name, &p.name);
            assert!(max_error(outline, &p.cut_line) < 1e-3);
        }
    }

    #[test]
    fn output_is_deterministic() {
        let nests = samples::nests();
        let opts = DxfOptions::default();
        let a = ok(nest_dxf("Dress", &nests, &opts));
        let b = ok(nest_dxf("Dress", &nests, &opts));
        assert_eq!(a, b);
        let pieces = samples::pieces("S", -8.0);
        assert_eq!(ok(pieces_dxf("x", &pieces, &opts)), ok(pieces_dxf("x", &pieces, &opts)));
    }

    #[test]
    fn notches_are_points_on_the_boundary_pointing_inwards() {
        let front = samples::front("M", 0.0);
        let bytes = ok(pieces_dxf("x", std::slice::from_ref(&front), &DxfOptions::default()));
        let drawing = ok(Drawing::load(&mut &bytes[..]).map_err(|e| ExportError::Dxf(e.to_string())));
        let block = drawing.blocks().find(|b| !b.name.starts_with('*'));
        let notches: Vec<&ModelPoint> = block
            .iter()
            .flat_map(|b| &b.entities)
            .filter(|e| e.common.layer == LAYER_NOTCHES)
            .filter_map(|e| if let EntityType::ModelPoint(p) = &e.specific { Some(p) } else { None })
            .collect();
        assert_eq!(notches.len(), front.notches.len());
        let n = &front.notches[0];
        let at = DVec2::new(notches[0].location.x, notches[0].location.y);
        assert!(at.distance(n.on_cut_line) < 0.5, "{at} vs {}", n.on_cut_line);
        let dir = DVec2::from_angle(notches[0].angle.to_radians());
        assert!(dir.dot(-n.outward) > 0.99, "{dir} vs {}", n.outward);

        let lines = DxfOptions { notch: NotchEntity::Line, ..Default::default() };
        let bytes = ok(pieces_dxf("x", std::slice::from_ref(&front), &lines));
        let text = String::from_utf8_lossy(&bytes);
        assert!(text.contains("LINE\r\n  8\r\n4\r\n"), "a notch line on layer 4");
    }

    #[test]
    fn bad_input_is_an_error() {
        let mut p = samples::pocket("M", 0.0);
        p.sew_line[1].y = f64::INFINITY;
        assert!(matches!(
            pieces_dxf("x", &[p], &DxfOptions::default()),
            Err(ExportError::NonFinite { what: "sew line", .. })
        ));
        let mut p = samples::pocket("M", 0.0);
        p.cut_line.truncate(2);
        assert!(matches!(
            pieces_dxf("x", &[p], &DxfOptions::default()),
            Err(ExportError::DegenerateOutline { points: 2, .. })
        ));
        let opts = DxfOptions { decimals: 13, ..Default::default() };
        assert!(matches!(pieces_dxf("x", &[], &opts), Err(ExportError::BadOption { option: "decimals", .. })));
        assert!(matches!(read_outlines(b"not a dxf"), Err(ExportError::Dxf(_))));
    }

    #[test]
    fn names_survive_the_round_trip() {
        let names = ["Größe ✓", "back\\slash ^caret", "two\nlines\ttab", "plain"];
        let pieces: Vec<PatternPiece> = names
            .iter()
            .map(|n| {
                let mut p = samples::pocket("M", 0.0);
                p.name = n.to_string();
                p
            })
            .collect();
        let bytes = ok(pieces_dxf("x", &pieces, &DxfOptions::default()));
        assert!(bytes.is_ascii(), "7-bit DXF");
        let read: Vec<String> = ok(read_outlines(&bytes)).into_iter().map(|(n, _)| n).collect();
        assert_eq!(read, names);
        assert_eq!(dxf_string("a^b\\c\u{1F600}é\r"), "a^ b\\U+005Cc?\\U+00E9^M");
        assert_eq!(dxf_string(&"x".repeat(300)).len(), MAX_STRING);
        assert_eq!(dxf_string(&"é".repeat(100)).len(), 7 * (MAX_STRING / 7));
    }

    #[test]
    fn block_names_are_legal_and_unique() {
        let mut used = BTreeSet::new();
        assert_eq!(block_name(&mut used, "front & <side>"), "FRONT____SIDE_");
        assert_eq!(block_name(&mut used, "front & <side>"), "FRONT____SIDE__2");
        assert_eq!(block_name(&mut used, ""), "PIECE");
        let long = "a".repeat(40);
        assert_eq!(block_name(&mut used, &long).len(), MAX_BLOCK_NAME);
        let second = block_name(&mut used, &long);
        assert_eq!(second.len(), MAX_BLOCK_NAME);
        assert!(second.ends_with("_2"));
        assert_eq!(block_name(&mut used, "Größe"), "GR__E");
    }
}
