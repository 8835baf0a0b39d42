//! SVG drawings of pattern pieces at true scale (SVG 1.1).
//!
//! # Contract
//!
//! - **Format**: a standalone SVG 1.1 document (UTF-8, `version="1.1"`,
//!   no scripts, no CSS, no external references) that a browser shows and an
//!   XML parser reads.
//! - **Scale and units**: true scale. The root's `width` and `height` are in
//!   `mm` and its `viewBox` spans the same numbers, so one user unit is one
//!   millimetre — printed at 100 % the pieces have their real size.
//! - **Axes**: the pieces' y axis points up, SVG's down; every point is
//!   written as `(x − x₀, y₀ − y)` so the drawing is not mirrored (text
//!   included).
//! - **Content** ([`pieces_svg`]): one `<g id=… class="piece">` per piece
//!   (its `<title>` is the piece's name), pieces side by side without
//!   overlap ([`ShelfLayout`]); the cut line solid, the sew line dashed,
//!   notches as short lines from the cut line inwards, the grain line with an
//!   arrowhead at its end point, internal lines, and text with the piece's
//!   name, size and quantity.
//! - **Graded nest** ([`nest_svg`]): one `<g class="piece">` per piece with
//!   one `<g class="size">` per size, smallest to largest, all sizes overlaid
//!   as the caller aligned them (stack point at the origin, grain parallel);
//!   each size has its own stroke colour, named in a legend.
//! - **Text**: every text (names of pieces, sizes, styles — user input) is
//!   XML-escaped; characters XML 1.0 forbids are dropped. Element ids are
//!   built from the names (`[A-Za-z0-9_.-]`, anything else becomes `_`) and
//!   made unique with a `-2`, `-3`, … suffix.
//! - **Determinism**: the same input and options give the same bytes.
//!
//! # Failure modes
//!
//! None: the functions return the document. A line or polygon with a
//! non-finite point is left out; with no pieces the document is an empty
//! canvas of twice the margin.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use glam::DVec2;

use super::{fmt_num, piece_bounds, Bounds, NotchMark, ShelfLayout};
use crate::pattern::piece::PatternPiece;

/// How the SVG is drawn. All lengths are millimetres at true scale.
#[derive(Debug, Clone, PartialEq)]
pub struct SvgOptions {
    /// Placement of the pieces side by side. Default [`ShelfLayout::default`] (20 mm gap, 1600 mm rows).
    pub layout: ShelfLayout,
    /// Empty border around the drawing, mm. Default 10 mm.
    pub margin_mm: f64,
    /// Decimals of the coordinates written (count). Default 3 (µm).
    pub decimals: usize,
    /// Stroke width of the cut line, mm. Default 0.5 mm.
    pub cut_stroke_mm: f64,
    /// Stroke width of sew line, notches, grain and internal lines, mm. Default 0.3 mm.
    pub line_stroke_mm: f64,
    /// Dash and gap lengths of the sew line, mm. Default 4 mm dash, 2 mm gap.
    pub sew_dash_mm: [f64; 2],
    /// Length of a notch mark from the cut line inwards, mm (at most up to the sew line). Default 6 mm.
    pub notch_length_mm: f64,
    /// Length of the grain line's arrowhead, mm. Default 10 mm.
    pub grain_arrow_length_mm: f64,
    /// Width of the grain line's arrowhead at its base, mm. Default 5 mm.
    pub grain_arrow_width_mm: f64,
    /// Height of text (font size), mm. Default 8 mm.
    pub text_height_mm: f64,
    /// Distance between lines of text, as a multiple of the text height. Default 1.4.
    pub line_spacing: f64,
    /// Average glyph width as a fraction of the text height, used only to
    /// size the canvas around the legend. Default 0.6.
    pub text_width_factor: f64,
    /// Font family of all text. Default `sans-serif`.
    pub font_family: String,
    /// Colour of the cut line (any SVG colour). Default `#000000`.
    pub cut_colour: String,
    /// Colour of the sew line. Default `#404040`.
    pub sew_colour: String,
    /// Colour of notches. Default `#000000`.
    pub notch_colour: String,
    /// Colour of the grain line. Default `#1f4e9c`.
    pub grain_colour: String,
    /// Colour of internal lines. Default `#808080`.
    pub internal_colour: String,
    /// Colour of text. Default `#000000`.
    pub text_colour: String,
    /// Stroke colours of the sizes in a graded nest, smallest size first,
    /// repeated when there are more sizes. Default: the ten "tab10" colours.
    /// Empty: every size in [`SvgOptions::cut_colour`].
    pub size_colours: Vec<String>,
    /// Length of a size's colour sample in the nest legend, mm. Default 15 mm.
    pub legend_swatch_mm: f64,
    /// Space between a colour sample and its size name, mm. Default 3 mm.
    pub legend_swatch_gap_mm: f64,
}

impl Default for SvgOptions {
    fn default() -> Self {
        Self {
            layout: ShelfLayout::default(),
            margin_mm: 10.0,
            decimals: 3,
            cut_stroke_mm: 0.5,
            line_stroke_mm: 0.3,
            sew_dash_mm: [4.0, 2.0],
            notch_length_mm: 6.0,
            grain_arrow_length_mm: 10.0,
            grain_arrow_width_mm: 5.0,
            text_height_mm: 8.0,
            line_spacing: 1.4,
            text_width_factor: 0.6,
            font_family: "sans-serif".to_string(),
            cut_colour: "#000000".to_string(),
            sew_colour: "#404040".to_string(),
            notch_colour: "#000000".to_string(),
            grain_colour: "#1f4e9c".to_string(),
            internal_colour: "#808080".to_string(),
            text_colour: "#000000".to_string(),
            size_colours: [
                "#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22",
                "#17becf",
            ]
            .iter()
            .map(|c| c.to_string())
            .collect(),
            legend_swatch_mm: 15.0,
            legend_swatch_gap_mm: 3.0,
        }
    }
}

/// The pieces (typically all pieces of one size) side by side at true scale:
/// one `<g id=… class="piece">` per piece (module docs).
pub fn pieces_svg(pieces: &[PatternPiece], opts: &SvgOptions) -> String {
    let boxes: Vec<Option<Bounds>> = pieces.iter().map(piece_bounds).collect();
    let shifts = opts.layout.place(&boxes);
    let content = placed_bounds(&boxes, &shifts);
    let mut svg = Svg::new(opts, content, 0.0, 0.0, "Pattern pieces");
    let mut ids = BTreeSet::new();
    for (piece, &t) in pieces.iter().zip(&shifts) {
        let id = unique_id(&mut ids, &format!("piece-{}", slug(&piece.name)));
        svg.open_group(&id, "piece", &piece.name);
        let colours = Colours::plain(opts);
        svg.piece_geometry(piece, t, &colours);
        if let Some(b) = piece_bounds(piece) {
            let mut lines =
                vec![piece.name.clone(), format!("Size: {}", piece.size), format!("Quantity: {}", piece.quantity)];
            if piece.cut_pair {
                lines.push("Cut pair".to_owned());
            }
            svg.text_block(b.translated(t).centre(), &lines);
        }
        svg.close_group();
    }
    svg.finish()
}

/// `#rrggbb` of hue `h` (0–1 round the colour wheel) at 65 % saturation and
/// 42 % lightness (HSL): distinct, print-dark colours for many sizes.
fn hue(h: f64) -> String {
    let (s, l) = (0.65, 0.42);
    let c = (1.0 - (2.0 * l - 1.0f64).abs()) * s;
    let hp = (h.rem_euclid(1.0)) * 6.0;
    let x = c * (1.0 - (hp % 2.0 - 1.0).abs());
    let (r, g, b) = match hp as u32 {
        0 => (c, x, 0.0),
        1 => (x, c, 0.0),
        2 => (0.0, c, x),
        3 => (0.0, x, c),
        4 => (x, 0.0, c),
        _ => (c, 0.0, x),
    };
    let m = l - c / 2.0;
    let byte = |v: f64| ((v + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    format!("#{:02x}{:02x}{:02x}", byte(r), byte(g), byte(b))
}

/// The graded nest of a style: for every piece name all its sizes overlaid,
/// smallest to largest, as the caller aligned them; one `<g class="piece">`
/// per piece with one `<g class="size">` per size in the size's colour, and
/// a legend of the size names (module docs).
pub fn nest_svg(style: &str, nests: &[(String, Vec<PatternPiece>)], opts: &SvgOptions) -> String {
    // sizes in order of first appearance: the colour of a size is the same in every piece
    let mut sizes: Vec<&str> = Vec::new();
    for (_, graded) in nests {
        for p in graded {
            if !sizes.contains(&p.size.as_str()) {
                sizes.push(&p.size);
            }
        }
    }
    // one distinct colour per size: the palette, or evenly spaced hues where it is too short
    let colour_of = |size: &str| {
        let i = sizes.iter().position(|s| *s == size).unwrap_or(0);
        if opts.size_colours.is_empty() {
            opts.cut_colour.clone()
        } else if sizes.len() <= opts.size_colours.len() {
            opts.size_colours[i].clone()
        } else {
            hue(i as f64 / sizes.len() as f64)
        }
    };
    let boxes: Vec<Option<Bounds>> =
        nests.iter().map(|(_, graded)| graded.iter().map(piece_bounds).fold(None, Bounds::union_opt)).collect();
    let shifts = opts.layout.place(&boxes);
    let content = placed_bounds(&boxes, &shifts);

    let pitch = opts.text_height_mm * opts.line_spacing;
    let title = format!("Graded nest: {style}");
    let legend_rows = sizes.len() + 1;
    let band = legend_rows as f64 * pitch + opts.layout.gap_mm.max(0.0);
    let longest = sizes.iter().map(|s| s.chars().count()).chain([title.chars().count()]).max().unwrap_or(0);
    let legend_width = opts.legend_swatch_mm
        + opts.legend_swatch_gap_mm
        + longest as f64 * opts.text_height_mm * opts.text_width_factor;
    let mut svg = Svg::new(opts, content, band, legend_width, &title);

    // legend
    svg.open_group("legend", "legend", "Sizes");
    let (x0, y0) = (opts.margin_mm, opts.margin_mm + pitch * 0.5);
    svg.raw_text(x0, y0, "start", &title);
    for (i, size) in sizes.iter().enumerate() {
        let y = y0 + pitch * (i + 1) as f64;
        let colour = colour_of(size);
        svg.raw_line(x0, y, x0 + opts.legend_swatch_mm, y, &colour, opts.cut_stroke_mm);
        svg.raw_text(x0 + opts.legend_swatch_mm + opts.legend_swatch_gap_mm, y, "start", size);
    }
    svg.close_group();

    let mut ids = BTreeSet::from(["legend".to_string()]);
    for ((name, graded), &t) in nests.iter().zip(&shifts) {
        let id = unique_id(&mut ids, &format!("piece-{}", slug(name)));
        svg.open_group(&id, "piece", name);
        for piece in graded {
            let size_id = unique_id(&mut ids, &format!("{id}-size-{}", slug(&piece.size)));
            svg.open_group(&size_id, "size", &piece.size);
            let colours = Colours::single(&colour_of(&piece.size));
            svg.piece_geometry(piece, t, &colours);
            // the size's label beside its outline's rightmost point
            if let Some(right) = piece.sew_line.iter().copied().max_by(|a, b| a.x.total_cmp(&b.x)) {
                let at = right + t + DVec2::new(opts.text_height_mm, 0.0);
                svg.text_block(at, std::slice::from_ref(&piece.size));
            }
            svg.close_group();
        }
        if let Some(b) = graded.iter().map(piece_bounds).fold(None, Bounds::union_opt) {
            svg.text_block(b.translated(t).centre(), std::slice::from_ref(name));
        }
        svg.close_group();
    }
    svg.finish()
}

/// Union of the boxes after their shifts.
fn placed_bounds(boxes: &[Option<Bounds>], shifts: &[DVec2]) -> Option<Bounds> {
    boxes.iter().zip(shifts).map(|(b, t)| b.map(|b| b.translated(*t))).fold(None, Bounds::union_opt)
}

/// Stroke colours of one drawn piece.
struct Colours {
    cut: String,
    sew: String,
    notch: String,
    grain: String,
    internal: String,
}

impl Colours {
    /// The colours of the options, per kind of line.
    fn plain(o: &SvgOptions) -> Self {
        Self {
            cut: o.cut_colour.clone(),
            sew: o.sew_colour.clone(),
            notch: o.notch_colour.clone(),
            grain: o.grain_colour.clone(),
            internal: o.internal_colour.clone(),
        }
    }

    /// One colour for everything (a size in a nest).
    fn single(c: &str) -> Self {
        Self { cut: c.into(), sew: c.into(), notch: c.into(), grain: c.into(), internal: c.into() }
    }
}

/// The document being written, with its mapping from piece space (mm, y
/// up, after layout) to SVG user space (mm, y down).
struct Svg<'a> {
    out: String,
    opts: &'a SvgOptions,
    /// Piece-space x and y that map to the margin's corner (left edge, top edge of the content).
    left: f64,
    top: f64,
}

impl<'a> Svg<'a> {
    /// Starts the document for content within `content` (piece space), with
    /// `band` mm of space above it and at least `min_width` mm of width.
    fn new(opts: &'a SvgOptions, content: Option<Bounds>, band: f64, min_width: f64, title: &str) -> Self {
        let b = content.unwrap_or(Bounds { min: DVec2::ZERO, max: DVec2::ZERO });
        let margin = if opts.margin_mm.is_finite() { opts.margin_mm.max(0.0) } else { 0.0 };
        let width = b.size().x.max(min_width) + 2.0 * margin;
        let height = b.size().y + band + 2.0 * margin;
        let (w, h) = (fmt_num(width, opts.decimals), fmt_num(height, opts.decimals));
        let mut out = String::new();
        out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n");
        let _ = writeln!(
            out,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{w}mm\" height=\"{h}mm\" \
             viewBox=\"0 0 {w} {h}\" font-family=\"{}\" font-size=\"{}\">",
            attr(&opts.font_family),
            fmt_num(opts.text_height_mm, opts.decimals),
        );
        let _ = writeln!(out, "<title>{}</title>", text(title));
        Self { out, opts, left: b.min.x - margin, top: b.max.y + margin + band }
    }

    /// SVG coordinates of a piece-space point.
    fn map(&self, p: DVec2) -> (String, String) {
        let d = self.opts.decimals;
        (fmt_num(p.x - self.left, d), fmt_num(self.top - p.y, d))
    }

    /// `x,y x,y …` of the points shifted by `t`, `None` if fewer than `min`
    /// points or any point is not finite.
    fn points(&self, pts: &[DVec2], t: DVec2, min: usize) -> Option<String> {
        if pts.len() < min || pts.iter().any(|p| !p.is_finite()) {
            return None;
        }
        Some(
            pts.iter()
                .map(|&p| {
                    let (x, y) = self.map(p + t);
                    format!("{x},{y}")
                })
                .collect::<Vec<_>>()
                .join(" "),
        )
    }

    fn open_group(&mut self, id: &str, class: &str, title: &str) {
        let _ = writeln!(self.out, "<g id=\"{}\" class=\"{}\">", attr(id), attr(class));
        let _ = writeln!(self.out, "<title>{}</title>", text(title));
    }

    fn close_group(&mut self) {
        self.out.push_str("</g>\n");
    }

    /// Stroke attributes: colour, width and optional dashes.
    fn stroke(&self, colour: &str, width: f64, dash: Option<[f64; 2]>) -> String {
        let d = self.opts.decimals;
        let mut s = format!("fill=\"none\" stroke=\"{}\" stroke-width=\"{}\"", attr(colour), fmt_num(width, d));
        if let Some([a, b]) = dash {
            let _ = write!(s, " stroke-dasharray=\"{},{}\"", fmt_num(a, d), fmt_num(b, d));
        }
        s
    }

    /// A closed (`polygon`) or open (`polyline`) line through the points.
    fn poly(&mut self, pts: &[DVec2], t: DVec2, closed: bool, class: &str, stroke: &str) {
        let (tag, min) = if closed { ("polygon", 3) } else { ("polyline", 2) };
        if let Some(points) = self.points(pts, t, min) {
            let _ = writeln!(self.out, "<{tag} class=\"{class}\" points=\"{points}\" {stroke}/>");
        }
    }

    /// A straight line between two piece-space points.
    fn line(&mut self, a: DVec2, b: DVec2, class: &str, stroke: &str) {
        if !(a.is_finite() && b.is_finite()) {
            return;
        }
        let ((x1, y1), (x2, y2)) = (self.map(a), self.map(b));
        let _ =
            writeln!(self.out, "<line class=\"{class}\" x1=\"{x1}\" y1=\"{y1}\" x2=\"{x2}\" y2=\"{y2}\" {stroke}/>");
    }

    /// A line in SVG user space (legend).
    fn raw_line(&mut self, x1: f64, y1: f64, x2: f64, y2: f64, colour: &str, width: f64) {
        let d = self.opts.decimals;
        let stroke = self.stroke(colour, width, None);
        let _ = writeln!(
            self.out,
            "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" {stroke}/>",
            fmt_num(x1, d),
            fmt_num(y1, d),
            fmt_num(x2, d),
            fmt_num(y2, d)
        );
    }

    /// One line of text in SVG user space, vertically centred on `y`.
    fn raw_text(&mut self, x: f64, y: f64, anchor: &str, content: &str) {
        let d = self.opts.decimals;
        let _ = writeln!(
            self.out,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"{anchor}\" dominant-baseline=\"middle\" fill=\"{}\">{}</text>",
            fmt_num(x, d),
            fmt_num(y, d),
            attr(&self.opts.text_colour),
            text(content)
        );
    }

    /// Lines of text centred on a piece-space point.
    fn text_block(&mut self, centre: DVec2, lines: &[String]) {
        if !centre.is_finite() {
            return;
        }
        let pitch = self.opts.text_height_mm * self.opts.line_spacing;
        let x = centre.x - self.left;
        let y_mid = self.top - centre.y;
        let first = y_mid - pitch * (lines.len().saturating_sub(1)) as f64 * 0.5;
        for (i, line) in lines.iter().enumerate() {
            self.raw_text(x, first + pitch * i as f64, "middle", line);
        }
    }

    /// Cut line, sew line, notches, grain line and internal lines of a piece shifted by `t`.
    fn piece_geometry(&mut self, p: &PatternPiece, t: DVec2, c: &Colours) {
        let o = self.opts;
        let cut = self.stroke(&c.cut, o.cut_stroke_mm, None);
        self.poly(&p.cut_line, t, true, "cut", &cut);
        let sew = self.stroke(&c.sew, o.line_stroke_mm, Some(o.sew_dash_mm));
        self.poly(&p.sew_line, t, true, "sew", &sew);
        let notch = self.stroke(&c.notch, o.line_stroke_mm, None);
        for n in &p.notches {
            if let Some(mark) = NotchMark::of(n, &p.cut_line) {
                self.line(mark.start + t, mark.end(o.notch_length_mm) + t, "notch", &notch);
            }
        }
        let internal = self.stroke(&c.internal, o.line_stroke_mm, None);
        for l in &p.internal_lines {
            self.poly(&l.points, t, false, "internal", &internal);
        }
        self.grain(p.grain[0] + t, p.grain[1] + t, &c.grain);
    }

    /// The grain line from `a` to `b` with a filled arrowhead at `b`.
    fn grain(&mut self, a: DVec2, b: DVec2, colour: &str) {
        let o = self.opts;
        let stroke = self.stroke(colour, o.line_stroke_mm, None);
        self.line(a, b, "grain", &stroke);
        let Some(dir) = (b - a).try_normalize() else { return };
        let base = b - dir * o.grain_arrow_length_mm;
        let side = dir.perp() * (o.grain_arrow_width_mm * 0.5);
        if let Some(points) = self.points(&[b, base + side, base - side], DVec2::ZERO, 3) {
            let _ = writeln!(
                self.out,
                "<polygon class=\"grain-arrow\" points=\"{points}\" fill=\"{}\" stroke=\"none\"/>",
                attr(colour)
            );
        }
    }

    fn finish(mut self) -> String {
        self.out.push_str("</svg>\n");
        self.out
    }
}

/// `s` with the characters XML 1.0 forbids removed and `& < >` escaped (element content).
fn text(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for ch in s.chars() {
        match ch {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            c if xml_char(c) => out.push(c),
            _ => {}
        }
    }
    out
}

/// [`text`] plus quotes escaped (attribute values).
fn attr(s: &str) -> String {
    text(s).replace('"', "&quot;").replace('\'', "&apos;")
}

/// Whether XML 1.0 allows the character.
fn xml_char(c: char) -> bool {
    matches!(c, '\t' | '\n' | '\r' | '\u{20}'..='\u{D7FF}' | '\u{E000}'..='\u{FFFD}' | '\u{10000}'..='\u{10FFFF}')
}

/// The name as id material: ASCII letters, digits, `-`, `_`, `.`; anything else `_`.
fn slug(name: &str) -> String {
    let s: String =
        name.chars().map(|c| if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') { c } else { '_' }).collect();
    if s.is_empty() {
        "unnamed".to_string()
    } else {
        s
    }
}

/// `base`, or `base-2`, `base-3`, … if taken; records the result.
fn unique_id(used: &mut BTreeSet<String>, base: &str) -> String {
    let mut id = base.to_string();
    let mut k = 2;
    while used.contains(&id) {
        id = format!("{base}-{k}");
        k += 1;
    }
    used.insert(id.clone());
    id
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::export::samples;

    /// Parses the document and returns it with its root.
    fn parse(svg: &str) -> roxmltree::Document<'_> {
        match roxmltree::Document::parse(svg) {
            Ok(doc) => doc,
            Err(e) => panic!("SVG does not parse: {e}\n{svg}"),
        }
    }

    fn groups<'a>(doc: &'a roxmltree::Document<'a>, class: &str) -> Vec<roxmltree::Node<'a, 'a>> {
        doc.descendants().filter(|n| n.has_tag_name("g") && n.attribute("class") == Some(class)).collect()
    }

    #[test]
    fn pieces_svg_parses_with_one_group_per_piece() {
        let pieces = samples::pieces("M", 0.0);
        let svg = pieces_svg(&pieces, &SvgOptions::default());
        let doc = parse(&svg);
        let root = doc.root_element();
        assert_eq!(root.attribute("version"), Some("1.1"));
        let (w, h) = (root.attribute("width").unwrap_or(""), root.attribute("height").unwrap_or(""));
        assert!(w.ends_with("mm") && h.ends_with("mm"), "{w} {h}");
        let vb: Vec<f64> = root.attribute("viewBox").unwrap_or("").split(' ').filter_map(|v| v.parse().ok()).collect();
        assert_eq!(vb.len(), 4);
        assert_eq!(format!("{}mm", fmt_num(vb[2], 3)), w);
        let g = groups(&doc, "piece");
        assert_eq!(g.len(), pieces.len());
        // every group's title is the piece's name, unescaped by the parser
        for (g, p) in g.iter().zip(&pieces) {
            let title = g.children().find(|n| n.has_tag_name("title")).and_then(|n| n.text());
            assert_eq!(title, Some(p.name.as_str()));
            let id = g.attribute("id").unwrap_or("");
            assert!(id.chars().all(|c| c.is_ascii_alphanumeric() || "-_.".contains(c)), "{id}");
            assert_eq!(g.descendants().filter(|n| n.attribute("class") == Some("cut")).count(), 1);
            assert_eq!(g.descendants().filter(|n| n.attribute("class") == Some("sew")).count(), 1);
            assert_eq!(g.descendants().filter(|n| n.attribute("class") == Some("notch")).count(), 1);
            assert_eq!(g.descendants().filter(|n| n.attribute("class") == Some("grain-arrow")).count(), 1);
            let texts: Vec<&str> =
                g.descendants().filter(|n| n.has_tag_name("text")).filter_map(|n| n.text()).collect();
            assert_eq!(texts, [p.name.as_str(), &format!("Size: {}", p.size), &format!("Quantity: {}", p.quantity)]);
        }
        assert!(svg.contains("front &amp; &lt;side&gt;"));
        // ids are unique even for equal names
        let twice = vec![pieces[2].clone(), pieces[2].clone()];
        let doc2 = pieces_svg(&twice, &SvgOptions::default());
        let doc2 = parse(&doc2);
        let ids: Vec<&str> = groups(&doc2, "piece").iter().filter_map(|g| g.attribute("id")).collect();
        assert_eq!(ids, ["piece-pocket", "piece-pocket-2"]);
    }

    #[test]
    fn pieces_do_not_overlap_and_are_not_mirrored() {
        let pieces = samples::pieces("M", 0.0);
        let svg = pieces_svg(&pieces, &SvgOptions::default());
        let doc = parse(&svg);
        let boxes: Vec<(f64, f64, f64, f64)> = doc
            .descendants()
            .filter(|n| n.attribute("class") == Some("cut"))
            .map(|n| {
                let pts: Vec<(f64, f64)> = n
                    .attribute("points")
                    .unwrap_or("")
                    .split(' ')
                    .filter_map(|xy| xy.split_once(','))
                    .filter_map(|(x, y)| Some((x.parse().ok()?, y.parse().ok()?)))
                    .collect();
                pts.iter().fold((f64::MAX, f64::MAX, f64::MIN, f64::MIN), |b, &(x, y)| {
                    (b.0.min(x), b.1.min(y), b.2.max(x), b.3.max(y))
                })
            })
            .collect();
        assert_eq!(boxes.len(), 3);
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                let (a, b) = (boxes[i], boxes[j]);
                assert!(a.2 <= b.0 || b.2 <= a.0 || a.3 <= b.1 || b.3 <= a.1, "{a:?} overlaps {b:?}");
            }
        }
        // the front's curved side bulges to the right (+x) in the SVG too: not mirrored
        let front = &pieces[0];
        let right = front.cut_line.iter().map(|p| p.x).fold(f64::MIN, f64::max);
        let left = front.cut_line.iter().map(|p| p.x).fold(f64::MAX, f64::min);
        assert!(right > -left + 20.0);
        let b = boxes[0];
        let width = b.2 - b.0;
        assert!((width - (right - left)).abs() < 1e-3, "true scale: {width} vs {}", right - left);
    }

    #[test]
    fn more_sizes_than_the_palette_still_get_distinct_colours() {
        assert_eq!(hue(0.0), "#b12525");
        let colours: BTreeSet<String> = (0..12).map(|i| hue(f64::from(i) / 12.0)).collect();
        assert_eq!(colours.len(), 12);
    }

    #[test]
    fn nest_svg_has_a_subgroup_and_colour_per_size() {
        let nests = samples::nests();
        let opts = SvgOptions::default();
        let svg = nest_svg("Dress <A&B>", &nests, &opts);
        let doc = parse(&svg);
        let pieces = groups(&doc, "piece");
        assert_eq!(pieces.len(), nests.len());
        for (g, (_, graded)) in pieces.iter().zip(&nests) {
            let sizes: Vec<roxmltree::Node> =
                g.children().filter(|n| n.has_tag_name("g") && n.attribute("class") == Some("size")).collect();
            assert_eq!(sizes.len(), graded.len());
            for (i, (s, p)) in sizes.iter().zip(graded).enumerate() {
                let title = s.children().find(|n| n.has_tag_name("title")).and_then(|n| n.text());
                assert_eq!(title, Some(p.size.as_str()));
                let cut = s.descendants().find(|n| n.attribute("class") == Some("cut"));
                assert_eq!(cut.and_then(|n| n.attribute("stroke")), Some(opts.size_colours[i].as_str()));
            }
        }
        let legend: Vec<&str> = groups(&doc, "legend")
            .iter()
            .flat_map(|g| g.descendants().filter(|n| n.has_tag_name("text")).filter_map(|n| n.text()))
            .collect();
        assert_eq!(legend, ["Graded nest: Dress <A&B>", "S", "M", "L & XL"]);
    }

    #[test]
    fn svg_is_deterministic_and_survives_bad_input() {
        let nests = samples::nests();
        let opts = SvgOptions::default();
        assert_eq!(nest_svg("x", &nests, &opts), nest_svg("x", &nests, &opts));
        let mut bad = samples::pocket("M\u{0}\u{1b}", 0.0);
        bad.name = "\u{7}bell\u{FFFE}".to_string();
        bad.cut_line[0].x = f64::NAN;
        let svg = pieces_svg(&[bad], &opts);
        let doc = parse(&svg);
        assert_eq!(groups(&doc, "piece").len(), 1);
        assert!(!svg.contains("NaN"));
        assert!(parse(&pieces_svg(&[], &opts)).root_element().has_tag_name("svg"));
    }
}
