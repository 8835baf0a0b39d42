//! Feature human models on real fixtures: frames, size-chart fits, the
//! scan path on a re-meshed body, and bad input.

use std::collections::BTreeMap;

use glam::DVec3;
use grade3d::body::derive::{derive_features, DeriveOptions, FeatureError, Landmarks};
use grade3d::body::feature::FeatureBody;
use grade3d::body::measure::{measure, MeasurementId};
use grade3d::body::vocab::{CurveId, PointId};
use grade3d::geom::mesh::{MeshError, TriMesh};
use grade3d::geom::polyline::Polyline;
use grade3d::geom::simplify::{remesh_unrelated, SimplifyOptions};
use grade3d::mannequin::fit::{fit_size, FitOptions};
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::{BodyModel, MacroParams, MannequinParams};
use grade3d::mannequin::size_chart::{parse_csv, FigureType, Sex, SexSource, SizeChartError, SizeChartOptions};
use proptest::prelude::*;

mod common;
use common::{fixture_bodies, fixtures};

fn derive(mesh: TriMesh, lm: &Landmarks) -> FeatureBody {
    derive_features(mesh, lm, &DeriveOptions::default()).unwrap()
}

#[test]
fn every_fixture_point_has_a_sound_frame() {
    let mut worst = (f64::INFINITY, String::new());
    for (name, mesh, lm) in fixture_bodies() {
        let body = derive(mesh, &lm);
        // the fixtures' landmark files are of vocabulary version 2: every point but the arms'
        let required = PointId::ALL.iter().filter(|p| !grade3d::body::vocab::optional_point(**p)).count();
        assert_eq!(body.points.len(), required, "{name}");
        for (id, p) in &body.points {
            let t = p.frame.triple().abs();
            assert!(t >= 0.1, "{name}: frame at {id} has triple product {t}");
            if t < worst.0 {
                worst = (t, format!("{name} {id}"));
            }
        }
    }
    eprintln!("smallest |t1·(t2×n)| over all fixtures: {:.3} at {}", worst.0, worst.1);
}

/// Issue #18 item 5 (vocabulary version 3): the arm curves a sleeve needs,
/// on hm08 bodies across issue #7's population. Planted answers from
/// MakeHuman's own measures, drawn on the hm08 topology: the derived
/// upper-arm and wrist girths (sections across the arm through the outer
/// points) are within 8 % of MakeHuman's `upperarm-circ` and `wrist-circ`
/// rings; the arm line, over the top of the arm, is at least the straight
/// shoulder–elbow–wrist distance and at most 25 % more (a tape from the
/// acromion runs over the deltoid: 524 mm over a 457 mm chord on the
/// reference body); the two arms of the symmetric reference body agree to
/// 1 mm.
#[test]
fn the_arm_curves_follow_makehumans_arm_measures() {
    use grade3d::body::measure::girth_of;
    let model = BodyModel::embedded().unwrap();
    let rings = &model.data().rings;
    let ring_length = |mesh: &TriMesh, name: &str, mirrored: bool| {
        let pts: Vec<DVec3> = rings[name]
            .iter()
            .map(|&v| {
                let v = grade3d::geom::mesh::VertexId(u32::from(v));
                mesh.position(if mirrored { model.mirror(v) } else { v })
            })
            .collect();
        // a closed ring, whether or not its list repeats its first vertex
        let mut pts: Vec<DVec3> = pts;
        if pts.len() > 1 && pts.first() == pts.last() {
            pts.pop();
        }
        Polyline::new(pts, true).length()
    };
    let mut bodies: Vec<(String, TriMesh)> = vec![("reference".into(), {
        let mut p = MannequinParams::default();
        p.macros.gender = 0.0;
        model.build(&p).unwrap()
    })];
    for p in grade3d::mannequin::population::sample_population(40, 13).into_iter().step_by(5) {
        bodies.push((p.name.clone(), model.build(&p.params).unwrap()));
    }
    for (name, mesh) in bodies {
        let lm = hm08_landmarks(model, &mesh, &Default::default()).unwrap();
        let body = derive(mesh.clone(), &lm);
        let g = |c: CurveId| girth_of(&body.curves[&c].polyline, body.curves[&c].plane.as_ref());
        for (side, mirrored, [upper, wrist, line], [s, e, w]) in [
            (
                "left",
                false,
                [CurveId::UpperArmLeft, CurveId::WristLeft, CurveId::ArmLineLeft],
                [PointId::ShoulderLeft, PointId::ElbowLeft, PointId::WristLeft],
            ),
            (
                "right",
                true,
                [CurveId::UpperArmRight, CurveId::WristRight, CurveId::ArmLineRight],
                [PointId::ShoulderRight, PointId::ElbowRight, PointId::WristRight],
            ),
        ] {
            // MakeHuman's rings list the left arm's vertices (+X); the right is their mirror
            let (mu, mw) = (ring_length(&mesh, "upperarm-circ", mirrored), ring_length(&mesh, "wrist-circ", mirrored));
            let (gu, gw) = (g(upper), g(wrist));
            let p = |id: PointId| body.points[&id].position;
            let chord = p(s).distance(p(e)) + p(e).distance(p(w));
            let arm = body.curves[&line].polyline.length();
            eprintln!(
                "{name} {side}: upper arm {:.0}/{:.0} mm, wrist {:.0}/{:.0} mm, arm line {:.0} mm over {:.0}",
                gu * 1e3,
                mu * 1e3,
                gw * 1e3,
                mw * 1e3,
                arm * 1e3,
                chord * 1e3
            );
            assert!((gu / mu - 1.0).abs() < 0.08, "{name} {side}: upper arm {gu} vs MakeHuman's {mu}");
            assert!((gw / mw - 1.0).abs() < 0.08, "{name} {side}: wrist {gw} vs MakeHuman's {mw}");
            assert!(arm >= chord * 0.999 && arm <= 1.25 * chord, "{name} {side}: arm line {arm} over {chord}");
        }
        if name == "reference" {
            for (l, r) in [(CurveId::UpperArmLeft, CurveId::UpperArmRight), (CurveId::ElbowLeft, CurveId::ElbowRight)] {
                assert!((g(l) - g(r)).abs() < 1e-3, "{l} {} vs {r} {}", g(l), g(r));
            }
        }
    }
}

/// The embedded hm08 model built with `macros` (no modifiers) and its
/// landmarks, as the population of issue #13 makes its bodies.
fn embedded_body(macros: MacroParams) -> (TriMesh, Landmarks) {
    let model = BodyModel::embedded().unwrap();
    let mesh = model.build(&MannequinParams { macros, modifiers: BTreeMap::new() }).unwrap();
    let lm = hm08_landmarks(model, &mesh, &Default::default()).unwrap();
    (mesh, lm)
}

/// Regression (issue #13): population body 36 (seed 13), a heavy, short,
/// muscular man, was refused with `degenerate frame at neck_left`
/// (|t1·(t2×n)| = 0.013): the medial end of MakeHuman's `shoulder-dist`, the
/// side neck point then, lay on the front of the full trapezius, where the
/// neck base runs along the shoulder line. The side neck points are now the
/// neck base's crossings with its coronal plane (`hm08_landmarks`).
#[test]
fn side_neck_points_on_a_full_trapezius_have_a_sound_frame() {
    let (mesh, lm) = embedded_body(MacroParams {
        gender: 1.0,
        age: 0.8845606370222278,
        muscle: 0.9433229434366929,
        weight: 0.9067075229879981,
        height: 0.09644097802691187,
        proportions: 0.5459620630190798,
        african: 0.06705245925776493,
        asian: 0.4226676162369004,
        caucasian: 0.5102799245053347,
    });
    let opts = DeriveOptions::default();
    let body = derive_features(mesh, &lm, &opts).unwrap_or_else(|e| panic!("refused: {e}"));
    for id in [PointId::NeckLeft, PointId::NeckRight] {
        let t = body.points[&id].frame.triple().abs();
        eprintln!("{id}: |t1·(t2×n)| = {t:.3}");
        assert!(t >= opts.min_frame_triple, "{id}: {t:.3}");
    }
}

/// Regression (issue #13): issue #13's population body `pop04-f-heavy-medium`
/// (a planted extreme: heaviest, oldest, least muscular woman) has thighs
/// that press into each other below the crotch, and the trousers were left
/// with 114 intersecting garment/body triangle pairs (62 on its scan-like
/// copy), all there. No two-legged garment can pass between such thighs
/// outside the body (`grade3d::body::contact`): the contact must be found,
/// named in a warning, and it must not be found on bodies whose legs stand
/// apart (every fixture body).
#[test]
fn pressed_thighs_are_found_and_named() {
    let (mesh, lm) = embedded_body(MacroParams {
        gender: 0.0,
        age: 1.0,
        muscle: 0.0,
        weight: 1.0,
        height: 0.5,
        proportions: 0.0,
        african: 0.0,
        asian: 1.0,
        caucasian: 0.0,
    });
    let body = derive(mesh, &lm);
    let c = body.thigh_contact.as_ref().expect("pop04's thighs press together");
    eprintln!("pop04: {:.1} mm below the crotch, {:.0} mm long", c.depth_below_crotch_mm, c.length_mm);
    // measured 16.6 mm below the crotch over 122 mm front to back; the
    // default needs 10 mm (legs standing apart reach at most 4.1 mm)
    assert!(c.depth_below_crotch_mm > 15.0 && c.depth_below_crotch_mm < 20.0, "{}", c.depth_below_crotch_mm);
    assert!(c.length_mm > 100.0 && c.length_mm < 150.0, "{}", c.length_mm);
    let w: Vec<_> = body.warnings.iter().filter(|w| w.code == "thighs-in-contact").collect();
    assert_eq!(w.len(), 1, "{:?}", body.warnings);
    assert_eq!(w[0].point, PointId::Crotch);
    // the contact moves with the body
    let (r, t) = (glam::DQuat::from_rotation_y(0.7), DVec3::new(0.3, -0.2, 1.1));
    let moved = body.transformed(r, t).unwrap();
    let mc = moved.thigh_contact.as_ref().unwrap();
    let p = c.points[0];
    assert!(mc.distance(r * p + t) < 1e-12);
    for (name, mesh, lm) in fixture_bodies() {
        let body = derive(mesh, &lm);
        assert_eq!(body.thigh_contact, None, "{name}");
        assert!(body.warnings.iter().all(|w| w.code != "thighs-in-contact"), "{name}");
    }
}

#[test]
fn degenerate_frame_is_rejected_naming_the_point() {
    let (_, mesh, mut lm) = fixture_bodies().swap_remove(1);
    // A crotch line laid along the centre front makes t(f1) ∥ t(f2).
    let body = derive(mesh.clone(), &lm);
    let cf = body.curves[&CurveId::CentreFront].polyline.clone();
    lm.curves.insert(CurveId::CrotchLine, Polyline::new(cf.points, true));
    let e = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap_err();
    match e {
        FeatureError::DegenerateFrame { point, triple, .. } => {
            assert_eq!(point, PointId::Crotch);
            assert!(triple.abs() < 0.1);
        }
        other => panic!("expected a degenerate frame, got {other}"),
    }
}

fn fit_chart(figure: FigureType) -> BTreeMap<MeasurementId, f64> {
    let text = std::fs::read_to_string(fixtures().join("size-charts/astm-d5585-11-misses-partial.csv")).unwrap();
    let chart = parse_csv(&text, &SizeChartOptions { figure, ..Default::default() }).unwrap();
    assert_eq!(chart.rows.len(), 12);
    let model = BodyModel::embedded().unwrap();
    let mut worst: BTreeMap<MeasurementId, f64> = BTreeMap::new();
    for row in &chart.rows {
        let f = fit_size(model, row, &FitOptions::default()).unwrap();
        for (id, r) in &f.residuals {
            let e = r.error_mm().abs();
            assert!(e <= 5.0, "{figure:?} size {}: {id} off by {e:.2} mm", row.size);
            let w = worst.entry(*id).or_insert(0.0);
            *w = w.max(e);
        }
        assert_eq!(f.residuals.len(), row.targets.len());
    }
    eprintln!("{figure:?}: worst residual per measurement (mm): {worst:.3?}");
    worst
}

/// Issue #18 item 5: a chart that gives the arms (upper-arm girth and arm
/// length, as a retailer's chart for sleeves does) is fitted to them too:
/// MakeHuman's arm measure modifiers are in the embedded model. Every
/// target of every size within 5 mm, the arms' included; an arm girth out
/// of its plausible range is named.
#[test]
fn a_chart_with_arms_is_fitted_to_them() {
    let csv = "size,unit,stature,bust_girth,waist_girth,hip_girth,upper_arm_girth,arm_length\n\
               34,cm,162,84,66,92,26,56\n36,cm,164,88,70,96,27,56.5\n38,cm,166,92,74,100,28,57\n\
               40,cm,168,96,78,104,29.5,57.5\n42,cm,170,100,82,108,31,58\n44,cm,172,104,86,112,32.5,58.5\n";
    let chart = parse_csv(csv, &SizeChartOptions::default()).unwrap();
    let model = BodyModel::embedded().unwrap();
    let opts = FitOptions::for_sex(chart.sex);
    let mut worst: BTreeMap<MeasurementId, f64> = BTreeMap::new();
    for row in &chart.rows {
        let f = fit_size(model, row, &opts).unwrap();
        assert_eq!(f.residuals.len(), row.targets.len());
        for (id, r) in &f.residuals {
            let e = r.error_mm().abs();
            assert!(e <= 5.0, "size {}: {id} off by {e:.2} mm", row.size);
            let w = worst.entry(*id).or_insert(0.0);
            *w = w.max(e);
        }
        // and the fitted body measures so
        let m = measure(&f.body, &Default::default());
        for id in [MeasurementId::UpperArmGirth, MeasurementId::ArmLength] {
            assert!((m[&id] - row.targets[&id]).abs() <= 5e-3, "size {}: {id} {}", row.size, m[&id]);
        }
    }
    eprintln!("a chart with arms: worst residual per measurement (mm): {worst:.3?}");
    let bad = csv.replace(",26,56\n", ",80,56\n");
    match parse_csv(&bad, &SizeChartOptions::default()) {
        Err(SizeChartError::OutOfRange { column, .. }) => assert_eq!(column, "upper_arm_girth"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn mens_chart_is_read_as_mens_and_fitted_from_a_male_body() {
    let text = std::fs::read_to_string(fixtures().join("size-charts/mens-36-46-in.csv")).unwrap();
    let chart = parse_csv(&text, &SizeChartOptions::default()).unwrap();
    assert_eq!((chart.sex, chart.sex_source), (Sex::Male, SexSource::Inferred));
    let model = BodyModel::embedded().unwrap();
    let opts = FitOptions::for_sex(chart.sex);
    let mut worst: BTreeMap<MeasurementId, f64> = BTreeMap::new();
    for row in &chart.rows {
        let f = fit_size(model, row, &opts).unwrap();
        assert_eq!(f.params.macros.gender, 1.0, "size {}: a male body", row.size);
        for (id, r) in &f.residuals {
            let e = r.error_mm().abs();
            assert!(e <= 5.0, "men's size {}: {id} off by {e:.2} mm", row.size);
            let w = worst.entry(*id).or_insert(0.0);
            *w = w.max(e);
        }
    }
    eprintln!("men's chart: worst residual per measurement (mm): {worst:.3?}");
}

#[test]
fn astm_sizes_fit_within_half_a_centimetre_curvy() {
    let w = fit_chart(FigureType::Curvy);
    assert_eq!(w.len(), 6);
}

#[test]
fn astm_sizes_fit_within_half_a_centimetre_straight() {
    fit_chart(FigureType::Straight);
}

#[test]
fn remeshed_scan_reproduces_girths_and_points() {
    let bodies = fixture_bodies();
    let mut worst_girth = (0.0f64, String::new());
    let mut worst_point = (0.0f64, String::new());
    for (name, mesh, lm) in bodies.into_iter().filter(|(n, ..)| n.starts_with("bodies/")) {
        let remeshed = remesh_unrelated(&mesh, 60_000, &SimplifyOptions::default()).unwrap();
        assert!((remeshed.face_count() as f64 - 60_000.0).abs() < 600.0, "{name}: {}", remeshed.face_count());
        let original = derive(mesh, &lm);
        let scan_lm = Landmarks { points: lm.points.clone(), curves: BTreeMap::new() };
        let scan = derive(remeshed, &scan_lm);
        let (mo, ms) = (measure(&original, &Default::default()), measure(&scan, &Default::default()));
        for (id, v) in &mo {
            if !id.is_girth() {
                continue;
            }
            let d = (ms[id] - v).abs() * 1e3;
            assert!(d <= 10.0, "{name}: {id} differs by {d:.2} mm");
            if d > worst_girth.0 {
                worst_girth = (d, format!("{name} {id}"));
            }
        }
        for (id, p) in &original.points {
            let d = scan.points[id].position.distance(p.position) * 1e3;
            assert!(d <= 10.0, "{name}: {id} moved {d:.2} mm: {:?} -> {:?}", p.position, scan.points[id].position);
            if d > worst_point.0 {
                worst_point = (d, format!("{name} {id}"));
            }
        }
    }
    eprintln!(
        "re-meshed scans: worst girth difference {:.2} mm ({}), worst point {:.2} mm ({})",
        worst_girth.0, worst_girth.1, worst_point.0, worst_point.1
    );
}

#[test]
fn unwelded_scan_gives_the_same_features() {
    // Every triangle with its own three vertices, as some exporters write.
    let (mesh, lm) = a_body();
    let mut pos = Vec::new();
    let mut tris = Vec::new();
    for t in mesh.triangles() {
        let base = pos.len() as u64;
        pos.extend(t.iter().map(|v| mesh.position(*v)));
        tris.push([base, base + 1, base + 2]);
    }
    let split = TriMesh::from_raw(pos, &tris).unwrap();
    assert_eq!(split.vertex_count(), 3 * mesh.face_count());
    let a = derive(mesh, &lm);
    let b = derive(split, &lm);
    for (id, p) in &a.points {
        assert!(b.points[id].position.distance(p.position) < 1e-9, "{id}");
    }
}

fn a_body() -> (TriMesh, Landmarks) {
    let (_, m, l) = fixture_bodies().swap_remove(0);
    (m, l)
}

#[test]
fn bad_meshes_are_typed_errors() {
    let (mesh, _) = a_body();
    let mut pos = mesh.positions().to_vec();
    pos[17].y = f64::NAN;
    let raw: Vec<[u64; 3]> = mesh.triangles().iter().map(|t| t.map(|v| u64::from(v.0))).collect();
    assert_eq!(TriMesh::from_raw(pos, &raw), Err(MeshError::NonFinite { vertex: 17 }));
    let mut bad = raw.clone();
    bad[5][1] = 1_000_000;
    assert!(matches!(
        TriMesh::from_raw(mesh.positions().to_vec(), &bad),
        Err(MeshError::IndexOutOfRange { face: 5, index: 1_000_000, .. })
    ));
    assert!(matches!(TriMesh::from_raw(vec![], &[]), Err(MeshError::Empty { .. })));
}

#[test]
fn implausible_stature_is_rejected() {
    let (mesh, lm) = a_body();
    for scale in [100.0, 0.001] {
        let scaled = mesh.map_positions(|p| p * scale).unwrap();
        let lm2 =
            Landmarks { points: lm.points.iter().map(|(k, v)| (*k, *v * scale)).collect(), curves: BTreeMap::new() };
        match derive_features(scaled, &lm2, &DeriveOptions::default()) {
            Err(FeatureError::BodySize { stature_m, .. }) => assert!(!(0.01..=100.0).contains(&stature_m)),
            other => panic!("scale {scale}: expected BodySize, got {other:?}"),
        }
    }
}

#[test]
fn missing_landmark_is_named() {
    let (mesh, mut lm) = a_body();
    lm.points.remove(&PointId::WaistLeft);
    match derive_features(mesh, &lm, &DeriveOptions::default()) {
        Err(FeatureError::MissingLandmarks { missing }) => assert_eq!(missing, vec![PointId::WaistLeft]),
        other => panic!("expected MissingLandmarks, got {other:?}"),
    }
}

#[test]
fn off_surface_and_non_finite_landmarks_are_named() {
    let (mesh, mut lm) = a_body();
    let mut far = lm.clone();
    *far.points.get_mut(&PointId::HipBack).unwrap() += DVec3::Z * -0.2;
    assert!(matches!(
        derive_features(mesh.clone(), &far, &DeriveOptions::default()),
        Err(FeatureError::LandmarkOffSurface { point: PointId::HipBack, .. })
    ));
    lm.points.insert(PointId::Crotch, DVec3::new(0.0, f64::INFINITY, 0.0));
    assert!(matches!(
        derive_features(mesh, &lm, &DeriveOptions::default()),
        Err(FeatureError::NonFiniteLandmark { point: PointId::Crotch })
    ));
}

#[test]
fn size_chart_errors_name_the_problem() {
    let o = SizeChartOptions::default();
    assert!(matches!(
        parse_csv("size,unit,bust_girth\n10,cm,36\n", &o),
        Err(SizeChartError::LikelyInches { ref column, .. }) if column == "bust_girth"
    ));
    assert!(matches!(
        parse_csv("size,bust_girth,wingspan\n10,90,170\n", &o),
        Err(SizeChartError::UnknownColumn { ref column }) if column == "wingspan"
    ));
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 8, ..ProptestConfig::default() })]
    /// Planted answer: translating a body and its landmarks translates
    /// every feature point by the same vector and leaves frames unchanged.
    #[test]
    fn translation_commutes_with_feature_derivation(dx in -2.0f64..2.0, dy in -2.0f64..2.0, dz in -2.0f64..2.0) {
        let (mesh, lm) = a_body();
        let t = DVec3::new(dx, dy, dz);
        let a = derive(mesh.clone(), &lm);
        let moved = mesh.map_positions(|p| p + t).unwrap();
        let lm2 = Landmarks { points: lm.points.iter().map(|(k, v)| (*k, *v + t)).collect(), curves: BTreeMap::new() };
        let b = derive(moved, &lm2);
        for (id, p) in &a.points {
            let q = &b.points[id];
            prop_assert!((q.position - p.position - t).length() < 1e-6, "{id}");
            prop_assert!((q.frame.n - p.frame.n).length() < 1e-6, "{id}");
        }
    }
}

#[test]
fn front_landmark_off_the_centre_line_is_refused() {
    let (_, mesh, mut lm) = fixture_bodies().swap_remove(1);
    // 5 cm to the body's left of the centre front line, still on the skin (snapped)
    let p = lm.points[&PointId::WaistFront];
    lm.points.insert(PointId::WaistFront, p + DVec3::new(0.05, 0.0, 0.0));
    match derive_features(mesh, &lm, &DeriveOptions::default()).unwrap_err() {
        FeatureError::OffMidline { point, offset_mm, limit_mm } => {
            assert_eq!(point, PointId::WaistFront);
            assert!(offset_mm > limit_mm && offset_mm <= 60.0, "{offset_mm}");
            assert_eq!(limit_mm, 30.0);
        }
        e => panic!("expected OffMidline, got {e}"),
    }
}

#[test]
fn front_landmark_near_the_midline_limit_is_graded_with_a_warning() {
    let (_, mesh, mut lm) = fixture_bodies().swap_remove(1);
    let clean = derive(mesh.clone(), &lm);
    assert!(clean.warnings.is_empty(), "{:?}", clean.warnings);
    // 20 mm to the body's left of the centre front line: above the 15 mm warning, below the 30 mm refusal
    let p = lm.points[&PointId::WaistFront];
    lm.points.insert(PointId::WaistFront, p + DVec3::new(0.02, 0.0, 0.0));
    let body = derive_features(mesh, &lm, &DeriveOptions::default()).expect("graded");
    let w: Vec<_> = body.warnings.iter().filter(|w| w.point == PointId::WaistFront).collect();
    assert_eq!(w.len(), 1, "{:?}", body.warnings);
    assert_eq!(w[0].code, "landmark-near-midline-limit");
    assert!(w[0].detail.contains("waist_front") && w[0].detail.contains("30 mm"), "{}", w[0].detail);
}

#[test]
fn thigh_landmark_above_the_crotch_is_refused() {
    let (_, mesh, mut lm) = fixture_bodies().swap_remove(1);
    // the left thigh point moved up the side of the leg to 20 mm above the crotch
    let crotch = lm.points[&PointId::Crotch];
    let t = lm.points[&PointId::ThighLeft];
    let up = grade3d::geom::query::closest_point(&mesh, DVec3::new(t.x, crotch.y + 0.02, t.z)).point;
    lm.points.insert(PointId::ThighLeft, up);
    let e = derive_features(mesh, &lm, &DeriveOptions::default()).unwrap_err();
    match e {
        FeatureError::LandmarkHeight { point, other, gap_mm, side, must, .. } => {
            assert_eq!((point, other, side, must), (PointId::ThighLeft, PointId::Crotch, "above", "below"), "{e}");
            assert!((10.0..=30.0).contains(&gap_mm), "{e}");
        }
        e => panic!("expected LandmarkHeight, got {e}"),
    }
}

#[test]
fn armscye_longer_than_the_chest_is_refused() {
    let (_, mesh, mut lm) = fixture_bodies().swap_remove(1);
    // the chest girth given as the left armscye: an armscye as long as the bust
    let body = derive(mesh.clone(), &lm);
    let chest = body.curves[&CurveId::Chest].polyline.clone();
    lm.curves.insert(CurveId::ArmscyeLeft, chest);
    match derive_features(mesh, &lm, &DeriveOptions::default()).unwrap_err() {
        FeatureError::ImplausibleGirth { curve, girth_mm, max_mm, .. } => {
            assert_eq!(curve, CurveId::ArmscyeLeft);
            assert!(girth_mm > max_mm, "{girth_mm} vs {max_mm}");
        }
        e => panic!("expected ImplausibleGirth, got {e}"),
    }
}

#[test]
fn armscye_section_through_the_torso_is_refused() {
    let (_, mesh, mut lm) = fixture_bodies().swap_remove(1);
    // the underarm point moved towards the midline: the armscye plane (through the
    // shoulder and underarm points, containing the depth axis) cuts into the torso
    let u = lm.points[&PointId::UnderarmLeft];
    let inward = grade3d::geom::query::closest_point(&mesh, DVec3::new(0.3 * u.x, u.y - 0.02, u.z)).point;
    lm.points.insert(PointId::UnderarmLeft, inward);
    // the point also lies 41 mm below its partner (refused by the pair check first): this test
    // is the girth bound's, so the pair check is out of its way
    let opts = DeriveOptions { max_pair_height_mm: 1000.0, ..DeriveOptions::default() };
    let e = derive_features(mesh, &lm, &opts).unwrap_err();
    match e {
        FeatureError::ImplausibleGirth { curve, girth_mm, max_mm, ref reason, .. } => {
            assert_eq!(curve, CurveId::ArmscyeLeft, "{e}");
            assert!(girth_mm > max_mm && reason.contains("chest"), "{e}");
        }
        e => panic!("expected ImplausibleGirth, got {e}"),
    }
}

/// Issue #17, item 3: supplied landmarks are checked as a pair and round the
/// limb, and a refusal names the landmark at fault.
#[test]
fn swapped_uneven_and_off_line_landmarks_are_refused_by_name() {
    let (_, mesh, lm) = fixture_bodies().swap_remove(0);
    let opts = DeriveOptions::default();
    // left and right swapped
    let mut swapped = lm.clone();
    let (l, r) = (lm.points[&PointId::HipLeft], lm.points[&PointId::HipRight]);
    swapped.points.insert(PointId::HipLeft, r);
    swapped.points.insert(PointId::HipRight, l);
    match derive_features(mesh.clone(), &swapped, &opts).unwrap_err() {
        FeatureError::SwappedSides { left, right, gap_mm } => {
            assert_eq!((left, right), (PointId::HipLeft, PointId::HipRight));
            assert!(gap_mm > 200.0, "{gap_mm}");
        }
        e => panic!("expected SwappedSides, got {e}"),
    }
    // a knee point 6 cm above its partner
    let mut uneven = lm.clone();
    let k = lm.points[&PointId::KneeRight];
    uneven.points.insert(PointId::KneeRight, grade3d::geom::query::closest_point(&mesh, k + DVec3::Y * 0.06).point);
    match derive_features(mesh.clone(), &uneven, &opts).unwrap_err() {
        FeatureError::PairHeight { left, right, gap_mm, limit_mm } => {
            assert_eq!((left, right), (PointId::KneeLeft, PointId::KneeRight));
            assert!(gap_mm > limit_mm && gap_mm < 70.0, "{gap_mm}");
        }
        e => panic!("expected PairHeight, got {e}"),
    }
    // the user's case: the knee point at the front of the knee, not its side. It was refused as
    // `curves ankle_left and leg_line_left do not cross near ankle_left_inner`; now by the knee
    let mut front = lm.clone();
    for (side, front_id) in [(PointId::KneeLeft, PointId::KneeLeftFront), (PointId::KneeRight, PointId::KneeRightFront)]
    {
        let p = front.points.get(&front_id).copied().unwrap_or_else(|| {
            let s = lm.points[&side];
            grade3d::geom::query::closest_point(&mesh, s + DVec3::new(-s.x.signum() * 0.05, 0.0, 0.08)).point
        });
        front.points.insert(side, p);
    }
    match derive_features(mesh, &front, &opts).unwrap_err() {
        FeatureError::OffSideLine { point, side, angle_deg, limit_deg, .. } => {
            assert_eq!((point, side), (PointId::KneeLeft, "outer side"));
            assert!(angle_deg > limit_deg, "{angle_deg}");
        }
        e => panic!("expected OffSideLine naming the knee, got {e}"),
    }
}
