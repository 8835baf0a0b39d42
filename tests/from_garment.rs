//! Issue #18, item 1: templates authored from a designed garment
//! (`grade3d::template::from_garment`), on MakeHuman's helper-skirt and
//! helper-tights (`fixtures/garments/`), whose design body is MakeHuman's
//! base mesh ([`BodyModel::base_mesh`]).
//!
//! Bars:
//! * round trip: the template graded back onto its design body lies within
//!   2 mm mean and 6 mm at the 95th percentile of the designed surface, in
//!   both directions (graded → designed, designed → graded);
//! * the authored skirt graded on every fixture body and ASTM size passes
//!   the bars of issues #7/#8 (`common/bars.rs`) but strain, which is held
//!   to [`SKIRT_STRAIN_CEILING`]: worst p95 4.38 %, female-slim-short-asian's
//!   back (3.90 % while its back could take two mirrored pairs of found
//!   darts; issue #14 caps them at two a piece, a pair counting two; it was
//!   8.99 % before every node below the hip hung from it, see
//!   `regression_every_skirt_node_below_the_hip_hangs_from_it`). On issue
//!   #7's population and its scan-like copies it reaches 4.56 %
//!   (pop00-f-slim-short's back), under the same ceiling
//!   (`tests/population.rs`, and the pop09 regression below);
//! * the styles drawn as curves (`template::drawn`, issue #18 item 5): see
//!   `drawn_styles_round_trip_and_the_a_line_skirt_grades`. The bodysuit
//!   (helper-tights) is held to the round trip only: its sleeves have no
//!   arm girths to follow (issue #18, item 5) and its feet are closed;
//!   graded on other bodies its sleeves and quarters tear (measured, see
//!   the notes).

use std::sync::OnceLock;

use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{RenderOptions, Renderer, RendererChoice};
use grade3d::collide::DepthRenderer;
use grade3d::geom::mesh::TriMesh;
use grade3d::geom::query::SphereIndex;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::BodyModel;
use grade3d::pattern::garment::DartSource;
use grade3d::pipeline::{block, grade, grade_with_darts, GradeOptions};
use grade3d::template::codec::decode;
use grade3d::template::format::{Relocation, Template};
use grade3d::template::from_garment::{author_from_garment, Authored, GarmentOptions, TubeCut};

mod common;
use common::fixture_bodies;

#[path = "common/authored.rs"]
mod authored;
#[path = "common/bars.rs"]
mod bars;
use authored::{design_body, garment, A_LINE_STRAIN_CEILING, SKIRT_STRAIN_CEILING};

/// How far decoding on the design body may put a node from where authoring
/// stored it, m.
const DECODE_TOLERANCE_M: f64 = 1e-3;

/// The princess dress's strain ceiling (p95 edge strain), a guard against
/// regressions, not the bar (issue #14's 4 %): measured 4.10 % at worst, on
/// `female-slim-short-asian`'s front side pieces (issue #18's notes).
const DRESS_STRAIN_CEILING: f64 = 0.045;

/// Round-trip bars, mm.
const ROUND_TRIP_MEAN_MM: f64 = 2.0;
/// See [`ROUND_TRIP_MEAN_MM`].
const ROUND_TRIP_P95_MM: f64 = 6.0;

fn renderer() -> &'static Renderer {
    static R: OnceLock<Renderer> = OnceLock::new();
    R.get_or_init(|| Renderer::new(RendererChoice::Auto).expect("a depth-map renderer"))
}

fn obstacle(mesh: &TriMesh) -> Obstacle {
    Obstacle {
        maps: renderer().depth_maps(mesh, &RenderOptions::default()).unwrap(),
        tree: WindingTree::new(mesh, &WindingOptions::default()),
    }
}

/// The two authored templates: the skirt cut at its sides, the tights (a
/// bodysuit) at the armscyes, sides and centre.
fn authored() -> &'static [(String, Authored)] {
    static A: OnceLock<Vec<(String, Authored)>> = OnceLock::new();
    A.get_or_init(|| {
        [("helper-skirt", TubeCut::Sides), ("helper-tights", TubeCut::SidesAndCentre)]
            .into_iter()
            .map(|(name, cut)| {
                let opts = GarmentOptions { cut, ..Default::default() };
                let a = author_from_garment(name, &[garment(name)], design_body(), &opts)
                    .unwrap_or_else(|e| panic!("{name}: {e:?}"));
                (name.to_owned(), a)
            })
            .collect()
    })
}

/// Mean and 95th percentile of `d`, mm.
fn mean_p95(mut d: Vec<f64>) -> (f64, f64) {
    d.sort_by(f64::total_cmp);
    (d.iter().sum::<f64>() / d.len() as f64 * 1e3, d[d.len() * 95 / 100] * 1e3)
}

#[test]
fn authored_templates_are_valid_documents_that_decode_exactly() {
    for (name, a) in authored() {
        let t = &a.template;
        // the JSON document passes the schema and every check, and reads back equal
        let back = Template::from_json(&t.to_json()).unwrap();
        assert_eq!(&back, t, "{name}");
        // decoding on the design body reproduces the stored nodes
        let worst = decode_off(t, design_body());
        eprintln!(
            "{name}: {} nodes, {} faces, pieces {:?}, ease {:?}, {} seams, {} notches, mirror pairs {:?}, unmapped {:?}; decode on the design body off by {:.2e} m",
            t.nodes.len(),
            t.faces.len(),
            a.pieces,
            a.girths,
            t.seams.len(),
            t.notches.len(),
            t.mirror_pairs,
            a.unmapped,
            worst
        );
        // (a ring node of a ring a stray node breaks is placed by Eq. (1) on the second
        // pass of authoring, the ring's offset solved without it: 0.12 mm on the bodysuit)
        assert!(worst < DECODE_TOLERANCE_M, "{name}: decode off by {worst}");
        assert!(!t.seams.is_empty() && !t.notches.is_empty(), "{name}");
    }
    let [(_, skirt), (_, tights)] = authored() else { panic!("two garments") };
    // planted answers: the skirt is a tube cut into front and back, its hip found
    assert_eq!(skirt.pieces, ["skirt-front", "skirt-back"]);
    assert!(skirt.girths.contains_key("hip"));
    // the bodysuit: two sleeves (upper, under) and four quarters, mirror pairs left/right
    assert_eq!(tights.pieces.len(), 8, "{:?}", tights.pieces);
    for g in ["waist", "hip", "thigh", "knee"] {
        assert!(tights.girths.contains_key(g), "tights lack {g}: {:?}", tights.girths);
    }
    assert!(tights.template.mirror_pairs.contains(&["tights-front-left".into(), "tights-front-right".into()]));
    assert!(tights.template.mirror_pairs.contains(&["tights-back-left".into(), "tights-back-right".into()]));
}

/// How far decoding `t` on its design body `body` puts its farthest node
/// from where the template stores it, m.
fn decode_off(t: &Template, body: &grade3d::body::feature::FeatureBody) -> f64 {
    let m = decode(t, body, Relocation::Eq1Frame).unwrap();
    m.positions.iter().zip(&t.nodes).map(|(p, n)| p.distance(glam::DVec3::from_array(n.reference))).fold(0.0, f64::max)
}

/// The round trip of `a` (method in the module docs), printed under
/// `name` after what was authored: `a` graded onto its design body `body`
/// (with `design` its obstacle), its graded surface against the designed
/// one both ways, each as (mean, p95) in mm; and the grade.
fn round_trip(
    name: &str,
    a: &Authored,
    body: &grade3d::body::feature::FeatureBody,
    design: &Obstacle,
) -> ((f64, f64), (f64, f64), grade3d::pipeline::Graded) {
    eprintln!(
        "{name}: {} nodes, {} faces, pieces {:?}, ease {:?}, unmapped {:?}",
        a.template.nodes.len(),
        a.template.faces.len(),
        a.pieces,
        a.girths,
        a.unmapped
    );
    let g = grade(&a.template, body, Some(design), "design", &GradeOptions::default()).unwrap();
    let graded = g.cut_mesh().unwrap();
    let (gi, si) = (SphereIndex::new(&graded), SphereIndex::new(&a.surface));
    let to_design = mean_p95(graded.positions().iter().map(|&q| si.closest_point(&a.surface, q).distance).collect());
    let to_graded = mean_p95(a.surface.positions().iter().map(|&q| gi.closest_point(&graded, q).distance).collect());
    eprintln!(
        "{name}: graded → designed mean {:.2} mm, p95 {:.2} mm; designed → graded mean {:.2} mm, p95 {:.2} mm",
        to_design.0, to_design.1, to_graded.0, to_graded.1
    );
    (to_design, to_graded, g)
}

/// Regression (issue #18): ARAP's iteration diverged on the authored
/// tights' back piece when let run 3000 iterations (the cap tried for the
/// dress's darted pieces), and the grade failed with `Factorisation("the
/// ARAP solution is not finite")`: a non-finite state passed for the best
/// one. The literal input: `helper-tights` graded on its design body with
/// `pattern.flatten.max_iterations` 3000. Planted: the grade succeeds and
/// every sew line is finite.
#[test]
fn regression_a_diverging_flattening_keeps_its_best_finite_state() {
    let (_, tights) = &authored()[1];
    let mut opts = GradeOptions::default();
    opts.pattern.flatten.max_iterations = 3000;
    let g = grade(&tights.template, design_body(), Some(&obstacle(&design_body().mesh)), "design", &opts)
        .expect("a finite flattening");
    for p in &g.pattern.pieces {
        assert!(p.sew_line.iter().all(|q| q.is_finite()), "{}", p.name);
    }
}

#[test]
fn round_trip_onto_the_design_body() {
    let obstacle = obstacle(&design_body().mesh);
    let mut failures = Vec::new();
    for (name, a) in authored() {
        let (to_design, to_graded, _) = round_trip(name, a, design_body(), &obstacle);
        for (what, (mean, p95)) in [("graded → designed", to_design), ("designed → graded", to_graded)] {
            if mean > ROUND_TRIP_MEAN_MM || p95 > ROUND_TRIP_P95_MM {
                failures.push(format!("{name} {what}: mean {mean:.2} mm, p95 {p95:.2} mm"));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn the_authored_skirt_passes_the_grade_bars_on_every_fixture() {
    let design = obstacle(&design_body().mesh);
    let mut b = bars::Bars::default();
    let mut failures = Vec::new();
    // its strain held to its ceiling: female-slim-short-asian's back reaches 4.38 % since issue
    // #14's cap of two found darts a piece counts a mirrored pair as two
    b.open_templates.push(("helper-skirt".into(), SKIRT_STRAIN_CEILING));
    for (name, a) in authored().iter().filter(|(n, _)| n == "helper-skirt") {
        let t = &a.template;
        let plan = block(t, design_body(), Some(&design), &GradeOptions::default()).unwrap();
        for (body_name, mesh, lm) in fixture_bodies() {
            let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
            let o = obstacle(&body.mesh);
            match grade_with_darts(t, &body, Some(&o), &body_name, &GradeOptions::default(), DartSource::Block(&plan)) {
                Ok(g) => b.check(t, &body, &o, &g, &body_name, false),
                Err(e) => failures.push(format!("{name} on {body_name}: {e}")),
            }
        }
    }
    eprintln!("{} grades", b.grades);
    b.report();
    failures.extend(b.failures);
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// Regression (the literal failing input): the authored skirt on issue #7's
/// population body 39 (`sample_population(40, 13)`, pop39-m-average-short).
/// A node lofted 4.6 cm above the hip on the design body was tied to
/// `hip_left`; on this short body it came within 3 cm of the hip's plane,
/// decoding took it for a second ring node at that point, and the edge to
/// the first had no length ("attached points 0 and 1 coincide"). Free nodes
/// are no longer tied to a ring girth's points.
/// Regression (issue #18): the authored skirt's front strained 8.99 % p95
/// on ASTM size 0 and 10.4 % on pop13-f-slim-short (3.0 % on its design
/// body), darts or none. Its nodes between the hip and the crotch (the
/// garment goes round the trunk there, not round both legs) and its
/// centre-front hem nodes (the hem dips there: no closed section within
/// 3 cm above them) were left to Eq. (1), tied to the crotch point and the
/// knees, and swung with those points' frames on other bodies. Every node
/// below the hip line now hangs from it.
#[test]
fn regression_every_skirt_node_below_the_hip_hangs_from_it() {
    let (_, skirt) = &authored()[0];
    let t = &skirt.template;
    let hip = grade3d::template::girth::girth_plane(design_body(), grade3d::body::vocab::CurveId::Hip).unwrap();
    let below: std::collections::BTreeSet<u32> = t.below.iter().map(|b| b.node).collect();
    let loose: Vec<(usize, String, f64)> = t
        .nodes
        .iter()
        .enumerate()
        .map(|(i, n)| (i, n.point.to_string(), -hip.signed_distance(glam::DVec3::from_array(n.reference))))
        .filter(|(i, _, drop)| *drop > 0.02 && !below.contains(&(*i as u32)))
        .collect();
    assert!(loose.is_empty(), "nodes below the hip left to Eq. (1): {loose:?}");
    // and the skirt declares that its found darts follow a pattern maker's rules
    assert!(t.defaults.guided_darts);
}

/// Issue #18: the authored skirt's darts, decided on its design body, are
/// drafted as a pattern maker drafts a skirt's (`GradingDefaults::guided_darts`):
/// waist darts in mirrored pairs, each opening on the waist edge and ending
/// above the hip line, each opening by the least intake in the piece as cut,
/// a pair's two openings within 10 % of each other. Before: a horizontal dart
/// from the side seam at the thigh, one back waist dart without its partner,
/// and (with the hanging region open) slits from the hem 58–70 cm long.
#[test]
fn the_authored_skirts_darts_are_mirrored_waist_darts() {
    use grade3d::pattern::darts::DartOrigin;
    let (_, skirt) = &authored()[0];
    let t = &skirt.template;
    let design = obstacle(&design_body().mesh);
    let g = grade_with_darts(t, design_body(), Some(&design), "design", &GradeOptions::default(), DartSource::Decide)
        .unwrap();
    let hip = grade3d::template::girth::girth_plane(design_body(), grade3d::body::vocab::CurveId::Hip).unwrap();
    let plan = &g.pattern.dart_plan.found;
    assert!(!plan.is_empty() && plan.len().is_multiple_of(2), "{plan:?}");
    for r in &g.pattern.reports {
        for pair in r.found_darts.chunks(2) {
            assert_eq!(pair.len(), 2, "{}: {pair:?}", r.name);
            assert_eq!((pair[0].origin, pair[1].origin), (DartOrigin::Found, DartOrigin::Mirrored));
            // the apexes mirror each other across the body's mid-plane (x = 0 on the base mesh)
            let (a, b) = (pair[0].apex, pair[1].apex);
            assert!((a.x + b.x).abs() < 0.015 && (a.y - b.y).abs() < 0.015, "{a} {b}");
        }
    }
    for d in plan {
        let (mouth, apex) = (g.cut_positions[d.chain[0]], g.cut_positions[d.chain[d.chain.len() - 1]]);
        let (m, a) = (hip.signed_distance(mouth), hip.signed_distance(apex));
        assert!(m > a && a > 0.0, "{}: mouth {m:.3} m, apex {a:.3} m above the hip", d.name);
    }
    for p in &g.pattern.pieces {
        let openings: Vec<f64> = p
            .internal_lines
            .iter()
            .filter(|l| l.name.starts_with("dart_auto"))
            .map(|l| l.points[0].distance(l.points[l.points.len() - 1]))
            .collect();
        eprintln!("{}: dart openings {openings:.1?} mm", p.name);
        for pair in openings.chunks(2) {
            assert!(pair.iter().all(|&o| o >= 3.0), "{}: {pair:?}", p.name);
            assert!((pair[0] - pair[1]).abs() <= 0.1 * pair[0].max(pair[1]), "{}: {pair:?}", p.name);
        }
    }
}

#[test]
fn regression_the_authored_skirt_decodes_on_pop39() {
    use grade3d::mannequin::population::sample_population;
    let model = BodyModel::embedded().unwrap();
    let p = &sample_population(40, 13)[39];
    assert_eq!(p.name, "pop39-m-average-short");
    let mesh = model.build(&p.params).unwrap();
    let lm = hm08_landmarks(model, &mesh, &Default::default()).unwrap();
    let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
    let (_, skirt) = &authored()[0];
    let t = &skirt.template;
    decode(t, &body, Relocation::Eq1Frame).unwrap();
    // no free node is tied to a point of the hip, the girth the skirt has a ring on
    let ring: std::collections::BTreeSet<u32> = grade3d::template::girth::ring_nodes(
        t,
        design_body(),
        &decode(t, design_body(), Relocation::Eq1Frame).unwrap().positions,
        grade3d::body::vocab::CurveId::Hip,
        &[],
    )
    .into_iter()
    .collect();
    for (i, n) in t.nodes.iter().enumerate() {
        if n.point.to_string().starts_with("hip_") {
            assert!(ring.contains(&(i as u32)), "node {i} is tied to {} but is no ring node", n.point);
        }
    }
}

/// Regression (the literal failing inputs, issue #7's population,
/// `sample_population(40, 13)`): the authored skirt on pop15-m-slim-tall
/// had 15 flipped triangles in its front, and on pop09-m-slim-short's
/// scan-like copy seam mismatches of 17.4, 6.4 and 5.2 mm. The cause was
/// the coarse template: interior nodes sampled one row inside the girth
/// lines (14 within 10 mm of the hip line, none of them ring nodes) made
/// slivers along them, which folded the refined garment (427 fine edges
/// with a dihedral angle past 90° on the design body). Nodes now keep the
/// sampling spacing from the outline too, and the contracted mesh is
/// flipped towards larger angles (`geom::flip`).
#[test]
fn regression_the_authored_skirt_on_pop15_and_pop09_scan() {
    use grade3d::body::derive::Landmarks;
    use grade3d::mannequin::population::{sample_population, scan_like};
    let model = BodyModel::embedded().unwrap();
    let pop = sample_population(40, 13);
    let (_, skirt) = &authored()[0];
    let t = &skirt.template;
    let design = obstacle(&design_body().mesh);
    let plan = block(t, design_body(), Some(&design), &GradeOptions::default()).unwrap();
    let mut b = bars::Bars::default();
    b.open_templates.push(("helper-skirt".into(), SKIRT_STRAIN_CEILING));
    for (i, scan) in [(15, false), (9, true)] {
        let p = &pop[i];
        let mesh = model.build(&p.params).unwrap();
        let lm = hm08_landmarks(model, &mesh, &Default::default()).unwrap();
        let (name, mesh, lm) = if scan {
            let s = scan_like(&mesh, 60_000, 1e-3, 13 ^ i as u64).unwrap();
            (format!("{}-scan", p.name), s, Landmarks { points: lm.points.clone(), curves: Default::default() })
        } else {
            (p.name.clone(), mesh, lm)
        };
        let body = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
        let o = obstacle(&body.mesh);
        let g =
            grade_with_darts(t, &body, Some(&o), &name, &GradeOptions::default(), DartSource::Block(&plan)).unwrap();
        for r in &g.pattern.reports {
            assert_eq!(r.distortion.flipped, 0, "{name} {}", r.name);
        }
        for s in &g.pattern.seams {
            assert!(s.mismatch_mm <= 1.0, "{name} {}: {} mm", s.name, s.mismatch_mm);
        }
        b.check(t, &body, &o, &g, &name, false);
    }
    b.report();
    assert!(b.failures.is_empty(), "{}", b.failures.join("\n"));
    // no node but the ring's within 10 mm of the hip line on the design body
    let hip = grade3d::template::girth::girth_plane(design_body(), grade3d::body::vocab::CurveId::Hip).unwrap();
    let near: Vec<usize> = t
        .nodes
        .iter()
        .enumerate()
        .filter(|(_, n)| !n.point.to_string().starts_with("hip_"))
        .filter(|(_, n)| hip.signed_distance(glam::DVec3::from_array(n.reference)).abs() < 0.01)
        .map(|(i, _)| i)
        .collect();
    assert!(near.is_empty(), "nodes {near:?} lie within 10 mm of the hip line");
}

/// Issue #18 item 2: an A-line skirt drawn as curves (seed 001) on the
/// design body — its waist, hip and hem as ellipses round the body's
/// girths (20 mm out at the waist, 25 mm at the hip, the hem 350 mm below
/// the hip and 60 mm out), its side seams straight — in four Coons panels
/// (front and back, waist to hip and hip to hem), authored like a designed
/// garment: it round-trips onto its design body within the bars, its hip
/// line (also the seam between the bands) stays one ring, and graded on
/// every fourth fixture body it meets the bars of issues #7/#8, strain and
/// area accuracy included (worst p95 2.44 %, |E_s| 0.59 %; they were 11.63 %
/// and 2.78 % before every node below the hip hung from it, and its lower
/// front needs darts below the hip: a cone between two ellipses of
/// different shape, 19 % p95 without them, `AutoDartOptions::hanging_strain_p95`).
#[test]
fn a_skirt_from_curves_round_trips_and_grades() {
    use grade3d::body::vocab::CurveId;
    use grade3d::template::from_curves::{panels_from_curves, CurvePanel, CurvesOptions};
    let body = design_body();
    // an ellipse round a girth: centre, half-width and half-depth of its section plus `out`, at height `y`
    let ellipse = |c: CurveId, out: f64, drop: f64| {
        let pts = &body.curves[&c].polyline.points;
        let centre = body.curves[&c].polyline.centroid();
        let half = |f: fn(&glam::DVec3) -> f64| pts.iter().map(|p| (f(p) - f(&centre)).abs()).fold(0.0, f64::max);
        (centre - glam::DVec3::Y * drop, half(|p| p.x) + out, half(|p| p.z) + out)
    };
    let rings =
        [ellipse(CurveId::Waist, 0.020, 0.0), ellipse(CurveId::Hip, 0.025, 0.0), ellipse(CurveId::Hip, 0.060, 0.35)];
    // the arc of ring `r` from angle a0 to a1 (0: the body's left side, +x; π/2: the front, +z)
    let arc = |r: usize, a0: f64, a1: f64| -> Vec<[f64; 3]> {
        let (c, ax, az) = rings[r];
        (0..=48)
            .map(|k| {
                let a = a0 + (a1 - a0) * k as f64 / 48.0;
                [c.x + ax * a.cos(), c.y, c.z + az * a.sin()]
            })
            .collect()
    };
    let side =
        |lower: usize, a: f64| vec![arc(lower, a, a)[0], arc(lower + 1, a, a)[0]].into_iter().rev().collect::<Vec<_>>();
    use std::f64::consts::PI;
    let mut panels = Vec::new();
    for (band, (upper, lower)) in [("upper", (0, 1)), ("lower", (1, 2))] {
        // front: from the left side (angle 0) round the front to the right side (π); back: π → 2π
        for (piece, a0) in [("front", 0.0), ("back", PI)] {
            panels.push(CurvePanel {
                name: format!("skirt-{piece}-{band}"),
                bottom: arc(lower, a0, a0 + PI),
                top: arc(upper, a0, a0 + PI),
                left: side(upper, a0),
                right: side(upper, a0 + PI),
                piece: None,
            });
        }
    }
    let pieces = panels_from_curves(&panels, &CurvesOptions::default()).unwrap();
    let a = author_from_garment(
        "curve-skirt",
        &pieces,
        body,
        &GarmentOptions { cut: TubeCut::None, interior_spacing: 0.5, ..Default::default() },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(a.girths.contains_key("hip"), "{:?}", a.girths);
    // round trip
    let design = obstacle(&body.mesh);
    let (to_design, to_graded, _) = round_trip("curve skirt", &a, body, &design);
    for (mean, p95) in [to_design, to_graded] {
        assert!(mean <= ROUND_TRIP_MEAN_MM && p95 <= ROUND_TRIP_P95_MM, "{mean} {p95}");
    }
    // graded on fixture bodies, every bar
    let go = GradeOptions::default();
    let plan = block(&a.template, body, Some(&design), &go).unwrap();
    let mut b = bars::Bars::default();
    for (name, mesh, lm) in fixture_bodies().into_iter().step_by(4) {
        let fb = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
        let o = obstacle(&fb.mesh);
        let g = grade_with_darts(&a.template, &fb, Some(&o), &name, &go, DartSource::Block(&plan))
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        b.check(&a.template, &fb, &o, &g, &name, false);
    }
    b.report();
    assert!(b.failures.is_empty(), "{:#?}", b.failures);
}

/// Issue #18 item 5: the styles drawn as curves on the reference body
/// (`grade3d::template::drawn`): an A-line skirt, a sleeveless shift
/// dress, plain and with princess seams, and a T-shirt with set-in sleeves.
/// * Their fixtures (`fixtures/garments/*.curves.json`, route 2's input, and
///   `*.obj`, the sampled surface with one group a piece, route 1's) are
///   what the code writes (`cargo xtask data garments`).
/// * Each, authored from its OBJ, round-trips on the reference body within
///   the bars, and has two pieces (front and back: the girths that shape a
///   piece are lines in it, not seams), the princess dress six (a centre
///   and two sides, front and back), the T-shirt those six and four sleeve
///   pieces, each sleeve's cap sewn into its armhole (a seam between the
///   sleeve's front piece and the bodice's front side piece, its back piece
///   and the back side piece, on either arm), the sleeves mirror pairs.
/// * The A-line skirt, graded on every fixture body and ASTM size with its
///   block's darts, passes the #7/#8 bars (`common/bars.rs`), its strain
///   held to an open ceiling ([`A_LINE_STRAIN_CEILING`]).
#[test]
fn drawn_styles_round_trip_and_the_a_line_skirt_grades() {
    use grade3d::io::obj::read_obj_panels;
    use grade3d::template::drawn;
    let body = grade3d::template::library::reference_body().unwrap();
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/garments");
    let (a_line, dress, princess, tee) = (
        drawn::ALineOptions::default(),
        drawn::ShiftDressOptions::default(),
        drawn::ShiftDressOptions::princess(),
        drawn::TShirtOptions::default(),
    );
    let two = ["front", "back"].as_slice();
    let six = ["front-left", "front", "front-right", "back-right", "back", "back-left"].as_slice();
    let ten = [
        "front-left",
        "front",
        "front-right",
        "back-right",
        "back",
        "back-left",
        "sleeve-left-front",
        "sleeve-left-back",
        "sleeve-right-front",
        "sleeve-right-back",
    ]
    .as_slice();
    let styles = [
        (
            "a-line-skirt",
            drawn::a_line_skirt_curves(&body, &a_line).unwrap(),
            drawn::a_line_skirt_surface(&body, &a_line).unwrap(),
            drawn::garment_options(),
            two,
        ),
        (
            "shift-dress",
            drawn::shift_dress_curves(&body, &dress).unwrap(),
            drawn::shift_dress_surface(&body, &dress).unwrap(),
            drawn::garment_options(),
            two,
        ),
        (
            "princess-dress",
            drawn::shift_dress_curves(&body, &princess).unwrap(),
            drawn::shift_dress_surface(&body, &princess).unwrap(),
            drawn::dress_garment_options(),
            six,
        ),
        (
            "t-shirt",
            drawn::t_shirt_curves(&body, &tee).unwrap(),
            drawn::t_shirt_surface(&body, &tee).unwrap(),
            drawn::dress_garment_options(),
            ten,
        ),
    ];
    let design = obstacle(&body.mesh);
    let mut a_line_template = None;
    for (name, curves, pieces, opts, piece_names) in styles {
        let stored: Vec<grade3d::template::from_curves::CurvePanel> =
            serde_json::from_str(&std::fs::read_to_string(root.join(format!("{name}.curves.json"))).unwrap()).unwrap();
        assert_eq!(stored, curves, "{name}: fixtures/garments is stale: run `cargo xtask data garments`");
        let read = read_obj_panels(&std::fs::read_to_string(root.join(format!("{name}.obj"))).unwrap()).unwrap();
        assert_eq!(read.len(), pieces.len(), "{name}");
        for (r, p) in read.iter().zip(&pieces) {
            // the reader numbers a piece's vertices by first use: compare triangle by triangle
            assert!(r.name == p.name && r.triangles.len() == p.triangles.len(), "{name} {}: stale", r.name);
            let off = r
                .triangles
                .iter()
                .zip(&p.triangles)
                .flat_map(|(a, b)| (0..3).map(move |k| r.positions[a[k] as usize].distance(p.positions[b[k] as usize])))
                .fold(0.0, f64::max);
            assert!(off < 1e-8, "{name} {}: stale by {off} m", r.name);
        }
        let names: Vec<&str> = read.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, piece_names, "{name}");
        let a = author_from_garment(name, &read, &body, &opts).unwrap_or_else(|e| panic!("{name}: {e}"));
        let (to_design, to_graded, g) = round_trip(name, &a, &body, &design);
        for r in &g.pattern.reports {
            eprintln!("{name} {} on its design body: p95 strain {:.2} %", r.name, r.distortion.strain_p95 * 100.0);
        }
        for (mean, p95) in [to_design, to_graded] {
            assert!(mean <= ROUND_TRIP_MEAN_MM && p95 <= ROUND_TRIP_P95_MM, "{name}: {mean} {p95}");
        }
        if name == "t-shirt" {
            let t = &a.template;
            let sewn = |p: &str, q: &str| {
                t.seams.iter().any(|s| [&s.panel_a, &s.panel_b] == [p, q] || [&s.panel_a, &s.panel_b] == [q, p])
            };
            for (sleeve, bodice) in [
                ("sleeve-left-front", "front-left"),
                ("sleeve-left-back", "back-left"),
                ("sleeve-right-front", "front-right"),
                ("sleeve-right-back", "back-right"),
            ] {
                assert!(sewn(sleeve, bodice), "t-shirt: {sleeve} is not sewn into {bodice}");
            }
            for pair in [["sleeve-left-front", "sleeve-right-front"], ["sleeve-left-back", "sleeve-right-back"]] {
                assert!(
                    t.mirror_pairs.iter().any(|m| m == &pair.map(String::from)),
                    "t-shirt: {pair:?} not a mirror pair: {:?}",
                    t.mirror_pairs
                );
            }
        }
        if name == "a-line-skirt" {
            assert!(a.girths.contains_key("hip"), "{:?}", a.girths);
            a_line_template = Some(a.template);
        }
    }
    let t = a_line_template.unwrap();
    // drafted symmetric (`GarmentOptions::symmetric_nodes_mm`): every node's mirror image across
    // the plane of its centre-line nodes (x of the hip's front and back ring nodes) is a node
    let centre = ["hip_front", "hip_back"]
        .iter()
        .map(|id| t.nodes.iter().find(|n| n.point.to_string() == *id).expect("ring node").reference[0])
        .sum::<f64>()
        / 2.0;
    let off = t
        .nodes
        .iter()
        .map(|n| {
            let m = glam::DVec3::new(2.0 * centre - n.reference[0], n.reference[1], n.reference[2]);
            t.nodes.iter().map(|o| glam::DVec3::from_array(o.reference).distance(m)).fold(f64::MAX, f64::min)
        })
        .fold(0.0, f64::max);
    eprintln!("a-line-skirt: every node's mirror image within {:.3} mm of a node", off * 1e3);
    assert!(off < 1e-3, "{off} m");
    let plan = block(&t, &body, Some(&design), &GradeOptions::default()).unwrap();
    // its block's found darts: none, or mirrored pairs (issue #14: two a piece at most)
    for piece in ["front", "back"] {
        let n = plan.found.iter().filter(|d| d.panel == piece).count();
        assert!(n == 0 || n == 2, "{piece}: {n} found darts in the block");
    }
    let (failures, _) = fixture_bar_failures(&t, &plan, A_LINE_STRAIN_CEILING);
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

/// Grades `t` on every fixture body and ASTM size (mirror-symmetric) with
/// its block's darts (`plan`) and checks the bars of issues #7 and #8
/// ([`bars::Bars::check`]), its strain held to `ceiling`: what fails, and
/// the worst sew-line difference of its mirror pairs there (mm).
fn fixture_bar_failures(
    t: &Template,
    plan: &grade3d::pattern::garment::DartPlan,
    ceiling: f64,
) -> (Vec<String>, bars::Worst) {
    let mut b = bars::Bars::default();
    b.open_templates.push((t.name.clone(), ceiling));
    let mut failures = Vec::new();
    for (name, mesh, lm) in fixture_bodies() {
        let fb = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
        let o = obstacle(&fb.mesh);
        match grade_with_darts(t, &fb, Some(&o), &name, &GradeOptions::default(), DartSource::Block(plan)) {
            Ok(g) => b.check(t, &fb, &o, &g, &name, false),
            Err(e) => failures.push(format!("{name}: {e}")),
        }
    }
    assert_eq!(b.grades + failures.len(), 20, "8 fixture bodies and 12 ASTM sizes");
    b.report();
    failures.extend(b.failures);
    (failures, b.mirror_mesh)
}

/// Issue #18 item 1: a piece's grain comes from its texture coordinates,
/// the pattern layout CLO3D, Browzwear and Marvelous Designer export (the
/// grain along `v`). Planted answers: the A-line skirt drawn on the
/// reference body, its pieces laid out as their front view (`u` across,
/// `v` up) and as that layout turned by 45° (a bias cut). The template's
/// grain runs within 10° of the layout's on the surface in both, and in the
/// front view at 0° and 45° (± 10°) from the vertical; without the layout
/// (or asked not to read it) the grain is the body's vertical.
#[test]
fn a_pieces_grain_comes_from_its_pattern_layout() {
    use grade3d::template::drawn::{a_line_skirt_surface, garment_options, ALineOptions};
    use grade3d::template::from_garment::GrainSource;
    let body = grade3d::template::library::reference_body().unwrap();
    let pieces = a_line_skirt_surface(&body, &ALineOptions::default()).unwrap();
    let laid_out = |turn_deg: f64| {
        let (c, s) = (turn_deg.to_radians().cos(), turn_deg.to_radians().sin());
        let mut out = pieces.clone();
        for p in &mut out {
            // seen from outside: the back's layout is its view from behind
            let across = if p.name == "back" { -1.0 } else { 1.0 };
            p.uv = p
                .positions
                .iter()
                .map(|q| {
                    let (u, v) = (across * q.x, q.y);
                    glam::DVec2::new(c * u - s * v, s * u + c * v)
                })
                .collect();
        }
        out
    };
    let grain_of = |a: &Authored, piece: &str| {
        let panel = a.template.panels.iter().find(|p| p.name == piece).unwrap();
        let (from, to) = (panel.grain.from as usize, panel.grain.to as usize);
        let d = glam::DVec3::from_array(a.template.nodes[to].reference)
            - glam::DVec3::from_array(a.template.nodes[from].reference);
        // in the front view, the plane the layout was taken from
        d.x.abs().atan2(d.y.abs()).to_degrees()
    };
    for (turn, from_vertical) in [(0.0, 0.0), (45.0, 45.0)] {
        let a = author_from_garment("laid-out", &laid_out(turn), &body, &garment_options()).unwrap();
        for piece in ["front", "back"] {
            let g = &a.grains[piece];
            assert_eq!(g.source, GrainSource::Uv, "{piece} at {turn}°");
            assert!(g.deviation_deg < 10.0, "{piece} at {turn}°: the pair runs {:.1}° off", g.deviation_deg);
            let angle = grain_of(&a, piece);
            eprintln!("{piece}, layout turned {turn}°: grain {angle:.1}° from vertical, {:.1}° off", g.deviation_deg);
            assert!((angle - from_vertical).abs() < 10.0, "{piece} at {turn}°: {angle:.1}° from vertical");
        }
    }
    let ignored = GarmentOptions { grain_from_uv: false, ..garment_options() };
    for (a, why) in [
        (author_from_garment("plain", &pieces, &body, &garment_options()).unwrap(), "no layout"),
        (author_from_garment("ignored", &laid_out(45.0), &body, &ignored).unwrap(), "layout not read"),
    ] {
        for piece in ["front", "back"] {
            assert_eq!(a.grains[piece].source, GrainSource::Vertical, "{why}");
            assert!(grain_of(&a, piece) < 10.0, "{why}: {piece}");
        }
    }
}

/// Regression (issue #18): with `keep_crossings`, a seam that crosses a
/// girth line away from the girth's feature points keeps its crossing. The
/// literal failing input: the shift dress drawn with princess seams, whose
/// seams cross the bust line 11 mm from `bust_front_left` (the chest line
/// 17 mm from `chest_back_left`). The crossing took that point's ring node,
/// and decoding placed ring nodes at their points: the node jumped along
/// the ring, off its seam (11.4 mm), and every graded seam stepped there.
/// Each such node now keeps its place along the girth (`ring_shift`, a
/// fraction of the girth's length), so decoding on the design body puts it
/// back on its seam. Also: `ease_at` limits the girth lines to those named,
/// and an unknown name is refused naming it.
#[test]
fn a_seam_crossing_a_girth_line_away_from_its_points_stays_on_the_seam() {
    use grade3d::body::vocab::{point_def, CurveId};
    use grade3d::geom::mesh::boundary_loops;
    use grade3d::geom::polyline::Polyline;
    use grade3d::template::drawn::{self, ShiftDressOptions};
    use grade3d::template::from_garment::FromGarmentError;
    use grade3d::template::girth::{girth_plane, RING_PLANE_TOLERANCE_M};
    let body = grade3d::template::library::reference_body().unwrap();
    let o = ShiftDressOptions { princess_seams: true, smooth_columns: true, ..Default::default() };
    let pieces = drawn::shift_dress_surface(&body, &o).unwrap();
    let mut opts = drawn::garment_options();
    opts.keep_crossings = true;
    opts.ease_at = vec!["bust".into(), "waist".into(), "hip".into()];
    let a = author_from_garment("princess-dress", &pieces, &body, &opts).unwrap();
    let t = &a.template;
    // only the girths named are girth lines
    assert_eq!(t.ease_mm.keys().collect::<Vec<_>>(), ["bust", "hip", "waist"], "{:?}", t.ease_mm);
    // the designed garment's seams: its pieces' outline edges
    let outline: Vec<Polyline> = pieces
        .iter()
        .flat_map(|p| {
            boundary_loops(&p.triangles)
                .into_iter()
                .map(|l| Polyline::new(l.iter().map(|&v| p.positions[v as usize]).collect(), true))
        })
        .collect();
    let off_seam =
        |p: glam::DVec3| outline.iter().filter_map(|l| l.closest(p)).map(|c| c.distance).fold(f64::MAX, f64::min);
    let shifted: Vec<(String, f64, f64)> = t
        .nodes
        .iter()
        .filter_map(|n| {
            let p = glam::DVec3::from_array(n.reference);
            n.ring_shift.map(|s| (n.point.to_string(), s, off_seam(p)))
        })
        .collect();
    for (point, shift, off) in &shifted {
        eprintln!("{point}: shifted {:+.4} of its girth, {:.2} mm off the designed seams", shift, off * 1e3);
    }
    // the princess seams cross the bust, waist and hip lines on both sides, front and back, away
    // from the girths' oblique points
    assert!(shifted.len() >= 8, "{shifted:?}");
    // every seam node on a girth line lies on the designed seams
    let seam_nodes: std::collections::BTreeSet<u32> = t
        .seams
        .iter()
        .flat_map(|s| s.edges.iter().flat_map(|&e| [t.edges[e as usize].start, t.edges[e as usize].end]))
        .collect();
    let girths = [CurveId::Bust, CurveId::Waist, CurveId::Hip];
    let planes: Vec<_> = girths.iter().map(|&c| girth_plane(&body, c).unwrap()).collect();
    let mut crossings = 0;
    for &v in &seam_nodes {
        let n = &t.nodes[v as usize];
        let def = point_def(n.point);
        let p = glam::DVec3::from_array(n.reference);
        let on_girth = girths
            .iter()
            .zip(&planes)
            .any(|(&c, plane)| (def.f1 == c || def.f2 == c) && plane.signed_distance(p).abs() < RING_PLANE_TOLERANCE_M);
        if on_girth {
            crossings += 1;
            let off = off_seam(p);
            assert!(off < 1.5e-3, "{}: {:.2} mm off the designed seams", n.point, off * 1e3);
        }
    }
    assert!(crossings >= 12, "{crossings} seam nodes on the girth lines");
    // decoding on the design body reproduces them
    let moved = decode_off(t, &body);
    assert!(moved < DECODE_TOLERANCE_M, "decode off by {moved} m");
    // an unknown girth is refused, naming it
    opts.ease_at = vec!["hips".into()];
    match author_from_garment("princess-dress", &pieces, &body, &opts) {
        Err(FromGarmentError::UnknownGirth { name, .. }) => assert_eq!(name, "hips"),
        other => panic!("{:?}", other.map(|a| a.template.name)),
    }
}

/// Issue #18: a symmetric garment drafted in halves, its girth lines split
/// by extra ring nodes, its caps flipped. The literal input: the shift
/// dress drawn with princess seams on the reference body, authored with
/// `ring_spacing_mm` 40, `mirror_halves` and caps flipped from 170°.
/// Before, extra ring nodes tied to a point they shared with its own ring
/// node landed on it in encoding (`ZeroChord` on the profile between
/// them); the two halves, each contracted on its own, were triangulated
/// differently (graded on the design body, front-left and front-right
/// flattened at 7.76 % and 3.64 % p95 strain, and no mirror pair was cut
/// as one); a crowded band took a node a round for 38 rounds, and the
/// contraction left caps down to 0.08° along the side seams (the sew lines
/// of a pair negotiated 3.9 mm apart). Planted answers: every arc of a
/// girth line between two nodes at most the spacing (plus a section edge);
/// the right half's nodes and triangles the mirror images of the left's;
/// the template decodes exactly on its design body; graded there, every
/// mirror pair is cut as one piece (sew lines within the mirror bar) and no
/// sew line crosses itself; no coarse angle under 1°.
#[test]
fn a_symmetric_dress_drafted_in_halves_with_its_girth_lines_split() {
    use grade3d::body::vocab::{point_def, CurveId};
    use grade3d::template::drawn::{self, ShiftDressOptions};
    use grade3d::template::girth::{girth_plane, RING_PLANE_TOLERANCE_M};
    let body = grade3d::template::library::reference_body().unwrap();
    let o = ShiftDressOptions { princess_seams: true, smooth_columns: true, ..Default::default() };
    let pieces = drawn::shift_dress_surface(&body, &o).unwrap();
    // the dress's own options, its lofted nodes walked from the girths' starts (as first drafted)
    let opts = GarmentOptions { bracketed_lofts: false, ..drawn::dress_garment_options() };
    let spacing_mm = opts.ring_spacing_mm;
    let a = author_from_garment("princess-dress", &pieces, &body, &opts).unwrap();
    let t = &a.template;
    assert!(a.unmapped.is_empty(), "{:?}", a.unmapped);
    let moved = decode_off(t, &body);
    assert!(moved < DECODE_TOLERANCE_M, "decode off by {moved} m");

    // girth lines: consecutive ring nodes (by angle about the girth's centroid) at most the spacing apart
    let section_edge_mm = 15.0;
    for curve in [CurveId::Bust, CurveId::Waist, CurveId::Hip] {
        let plane = girth_plane(&body, curve).unwrap();
        let centre = body.curves[&curve].polyline.centroid();
        let (e1, e2) = plane.basis();
        let mut ring: Vec<(f64, glam::DVec3)> = t
            .nodes
            .iter()
            .filter(|n| {
                let d = point_def(n.point);
                let p = glam::DVec3::from_array(n.reference);
                (d.f1 == curve || d.f2 == curve) && plane.signed_distance(p).abs() <= RING_PLANE_TOLERANCE_M
            })
            .map(|n| {
                let p = glam::DVec3::from_array(n.reference);
                ((p - centre).dot(e2).atan2((p - centre).dot(e1)), p)
            })
            .collect();
        ring.sort_by(|a, b| a.0.total_cmp(&b.0));
        let gap = (0..ring.len()).map(|k| ring[k].1.distance(ring[(k + 1) % ring.len()].1)).fold(0.0, f64::max) * 1e3;
        eprintln!("{curve}: {} ring nodes, widest gap {gap:.1} mm", ring.len());
        assert!(gap <= spacing_mm + section_edge_mm, "{curve}: a gap of {gap:.1} mm");
        assert!(t.nodes.iter().filter(|n| n.ring_shift.is_some()).count() > ring.len());
    }

    // the halves: mirror images across the body's mid-sagittal plane, the one the grade
    // symmetrises about (every left/right pair of feature points bisected). Drafted across the
    // plane through the hip's vertex centroid instead, the shoulder nodes mirrored 2.8 mm apart
    // across this one, the grade paired the refined halves by nearest vertices only, and the
    // found darts of a side piece were not mirrored onto its pair
    let ((n, d), _) = grade3d::refine::symmetry::body_plane(&body).unwrap();
    let side = |p: glam::DVec3| n.dot(p) - d;
    let mirror = |p: glam::DVec3| p - 2.0 * n * side(p);
    let positions: Vec<glam::DVec3> = t.nodes.iter().map(|n| glam::DVec3::from_array(n.reference)).collect();
    let mut worst_mm: f64 = 0.0;
    for &p in positions.iter().filter(|p| side(**p).abs() > 1e-6) {
        let m = mirror(p);
        worst_mm = worst_mm.max(positions.iter().map(|q| q.distance(m)).fold(f64::MAX, f64::min) * 1e3);
    }
    eprintln!("nodes: {} (worst mirror partner {worst_mm:.4} mm)", positions.len());
    assert!(worst_mm < 0.05, "a node's mirror partner {worst_mm:.4} mm off");
    // one node a corner (`one_node_a_corner`; without it every outline vertex within
    // `corner_span_mm` of a corner is a node: pairs 3.3 mm apart above the bust line)
    let closest_mm = positions
        .iter()
        .enumerate()
        .flat_map(|(i, p)| positions[i + 1..].iter().map(move |q| p.distance(*q)))
        .fold(f64::MAX, f64::min)
        * 1e3;
    eprintln!("closest nodes {closest_mm:.1} mm apart");
    assert!(closest_mm > 10.0, "two nodes {closest_mm:.1} mm apart");
    // a sleeveless armhole reaches past the armscye's plane: no node of it follows an arm point
    // (one was tied to `upper_arm_left`, and no fixture body, without arm landmarks, could be graded)
    let arm_ties: Vec<String> =
        t.nodes.iter().map(|n| n.point.to_string()).filter(|p| p.starts_with("upper_arm")).collect();
    assert!(arm_ties.is_empty(), "{arm_ties:?}");
    let faces_on = |sign: f64| {
        (0..t.faces.len())
            .filter(|&f| t.face_nodes(f).iter().map(|&v| side(positions[v as usize])).sum::<f64>() * sign > 0.0)
            .count()
    };
    assert_eq!(faces_on(1.0), faces_on(-1.0), "the halves' triangle counts");
    assert_eq!(faces_on(1.0) + faces_on(-1.0), t.faces.len());

    // graded on its design body: the pairs cut as one, no sew line crossing itself
    let g = grade(t, &body, Some(&obstacle(&body.mesh)), "design", &GradeOptions::default()).unwrap();
    assert_eq!(g.pattern.cut_pairs.len(), 2, "{:?}", g.pattern.cut_pairs);
    for pair in &g.pattern.cut_pairs {
        eprintln!("{:?}: sew lines {:.3} mm apart", pair.panels, pair.difference.sew_line_mm);
        assert!(pair.cut_as_pair && pair.difference.sew_line_mm <= bars::MIRROR_MM, "{pair:?}");
    }
    for r in &g.pattern.reports {
        eprintln!("{}: p95 strain {:.2} %", r.name, r.distortion.strain_p95 * 100.0);
        assert!(!r.sew_line_self_intersects, "{}", r.name);
    }
    // the contraction's caps flipped: no coarse angle under 1° (0.08° before)
    let least = (0..t.faces.len())
        .map(|f| {
            let [a, b, c] = t.face_nodes(f).map(|v| positions[v as usize]);
            grade3d::geom::flip::min_angle(a, b, c).to_degrees()
        })
        .fold(f64::MAX, f64::min);
    eprintln!("smallest coarse angle {least:.2}°");
    assert!(least > 1.0, "{least}°");
}

/// Issue #18: the princess dress (`fixtures/garments/princess-dress.obj`,
/// route 1, authored with `drawn::dress_garment_options`) graded on every
/// fixture body and ASTM size with its block's darts. The literal failing
/// input: on `female-heavy-tall-african` and `male-heavy-short-african`
/// the front side pieces' sew lines crossed themselves. Each armhole node
/// was tied to the shoulder or armpit point by Eq. (1): on the heavy man
/// one 60 mm from the armpit point dropped 91 mm, below its neighbour, and
/// the armhole folded back; and the lofted nodes of the princess seams
/// stood 17–23 mm off their bust ring node (arc fractions of the whole
/// girth). Planted: every armhole node is placed along the armscye
/// (`on_curve`, both armholes alike) and every lofted node carries its
/// brackets; the template decodes exactly on its design body; on every
/// body (mirror-symmetric) the bars of issues #7 and #8 hold
/// ([`bars::Bars::check`]: no self-crossing sew line, pairs cut as one
/// within 0.5 mm, ease within 5 mm, |E_s| within 2 %), the strain held to
/// [`DRESS_STRAIN_CEILING`], and each mirror pair's pieces are exact mirror
/// images (within 0.001 mm).
#[test]
fn the_princess_dress_keeps_its_armholes_and_seams_on_every_body() {
    use grade3d::io::obj::read_obj_panels;
    use grade3d::template::drawn::dress_garment_options;
    let body = grade3d::template::library::reference_body().unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/garments/princess-dress.obj");
    let pieces = read_obj_panels(&std::fs::read_to_string(path).unwrap()).unwrap();
    let t = author_from_garment("princess-dress", &pieces, &body, &dress_garment_options()).unwrap().template;
    let moved = decode_off(&t, &body);
    assert!(moved < DECODE_TOLERANCE_M, "decode off by {moved} m");
    let on = |side: &str| t.on_curve.iter().filter(|c| c.curve.to_string() == format!("armscye_{side}")).count();
    eprintln!("armhole nodes on the armscyes: {} left, {} right", on("left"), on("right"));
    assert!(on("left") >= 6 && on("left") == on("right"), "{} {}", on("left"), on("right"));
    assert!(!t.between.is_empty() && t.between.iter().all(|b| b.lower_bracket.is_some() && b.upper_bracket.is_some()));
    // the nodes left to Eq. (1) are the eased girths' ring nodes and the armholes' top corners at
    // the shoulder points: the neckline's are lofted from the chest line up past the neck base's
    // centroid (its back rises above it). Left to Eq. (1), the centre-back neck node was tied to
    // `chest_back` 170 mm below it and decoded 24.6–26.3 mm inside every body of the men's chart,
    // its pattern point jumping 7.8 mm between sizes 40 and 42 (regression)
    let placed: std::collections::BTreeSet<u32> = (t.between.iter().map(|b| b.node))
        .chain(t.below.iter().map(|b| b.node))
        .chain(t.on_curve.iter().map(|c| c.node))
        .collect();
    let eq1: Vec<String> = (0..t.nodes.len() as u32)
        .filter(|i| !placed.contains(i))
        .map(|i| t.nodes[i as usize].point.to_string())
        .filter(|p| !["bust", "waist", "hip", "shoulder_left", "shoulder_right"].iter().any(|g| p.starts_with(g)))
        .collect();
    assert!(eq1.is_empty(), "nodes left to Eq. (1), tied to {eq1:?}");

    let plan = block(&t, &body, Some(&obstacle(&body.mesh)), &GradeOptions::default()).unwrap();
    let (failures, mirror) = fixture_bar_failures(&t, &plan, DRESS_STRAIN_CEILING);
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
    // a mirror pair's second piece is its first's flattening mirrored (`pattern::mirror`): exact
    // images on these symmetric bodies (each flattened on its own: up to 0.05 mm apart here, and
    // 2.78 mm on a population body whose darted fronts stopped short of converging)
    assert!(mirror.0 <= 1e-3, "mirror pairs {:.4} mm apart at {}", mirror.0, mirror.1);
}

/// Issue #18, item 5 (the T-shirt's sleeves, first part): short set-in
/// sleeves drawn on the arm curves (route 2, `drawn::sleeve_curves`: a tube
/// on each arm from the eased armscye to the eased upper-arm girth, front
/// and back pieces) and authored from their surface (route 1). Planted:
/// four pieces, two mirror pairs; the nodes on the arm are tied to the
/// arm's points (`upper_arm_*`), so the round trip onto the design body
/// meets the bars (2 mm mean, 6 mm p95, both ways); and on a body whose
/// landmarks (vocabulary 2) give no arms the template is refused, naming
/// the arm point it lacks.
#[test]
fn sleeves_drawn_on_the_arms_round_trip_and_need_arms() {
    use grade3d::template::drawn::{garment_options, sleeves_surface, SleeveOptions};
    let body = grade3d::template::library::reference_body().unwrap();
    let pieces = sleeves_surface(&body, &SleeveOptions::default()).unwrap();
    let names: Vec<&str> = pieces.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["sleeve-left-front", "sleeve-left-back", "sleeve-right-front", "sleeve-right-back"]);
    let a = author_from_garment("sleeves", &pieces, &body, &garment_options()).unwrap();
    let t = &a.template;
    for side in ["left", "right"] {
        let pair = [format!("sleeve-{side}-front"), format!("sleeve-{side}-back")];
        assert!(t.seams.iter().filter(|s| [&s.panel_a, &s.panel_b] == [&pair[0], &pair[1]]).count() >= 2, "{side}");
        assert!(t.nodes.iter().any(|n| n.point.to_string() == format!("upper_arm_{side}")), "{side}");
    }
    assert!(
        t.mirror_pairs.contains(&["sleeve-left-front".into(), "sleeve-right-front".into()]),
        "{:?}",
        t.mirror_pairs
    );
    let design = obstacle(&body.mesh);
    let (to_design, to_graded, g) = round_trip("sleeves", &a, &body, &design);
    for r in &g.pattern.reports {
        eprintln!("sleeves {} on its design body: p95 strain {:.2} %", r.name, r.distortion.strain_p95 * 100.0);
    }
    for (mean, p95) in [to_design, to_graded] {
        assert!(mean <= ROUND_TRIP_MEAN_MM && p95 <= ROUND_TRIP_P95_MM, "sleeves: {mean} {p95}");
    }
    // a fixture body's landmarks give no arms
    let (name, mesh, lm) = fixture_bodies().into_iter().next().unwrap();
    let fb = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap();
    match grade(t, &fb, None, &name, &GradeOptions::default()) {
        Err(e) => assert!(e.to_string().contains("upper_arm_"), "{name}: {e}"),
        Ok(_) => panic!("{name}: sleeves graded on a body without arms"),
    }
}
