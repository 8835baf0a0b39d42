//! Feature human model benchmarks (issue #2): build a mannequin from
//! parameters, fit one size-chart row, derive features for a 60k-triangle
//! scan; issue #17: repair and frame a scan as it comes, and register the
//! body model to a 60k-triangle scan (its bar: ≤ 300 ms on two cores).
//! Run: `cargo bench --bench bodies`.
#![expect(missing_docs, reason = "criterion_group! generates undocumented items")]

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use grade3d::body::derive::{derive_features, DeriveOptions};
use grade3d::body::frame::{body_frame, FrameHints, FrameOptions};
use grade3d::geom::repair::{repair, RepairOptions};
use grade3d::geom::simplify::{remesh_unrelated, SimplifyOptions};
use grade3d::io::gltf::read_mesh;
use grade3d::io::landmarks::parse_landmarks;
use grade3d::mannequin::fit::{fit_size, FitOptions};
use grade3d::mannequin::model::{BodyModel, MannequinParams};
use grade3d::mannequin::population::{sample_population, scan_like};
use grade3d::mannequin::register::{register, RegisterOptions};
use grade3d::mannequin::size_chart::{parse_csv, SizeChartOptions};

fn benches(c: &mut Criterion) {
    let model = BodyModel::embedded().expect("embedded model");
    let mut params = MannequinParams::default();
    params.macros.gender = 0.0;
    params.modifiers.insert("torso/measure-waist-circ".into(), 0.3);
    c.bench_function("mannequin_build", |b| b.iter(|| model.build(&params).expect("build")));

    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures");
    let chart = parse_csv(
        &std::fs::read_to_string(root.join("size-charts/astm-d5585-11-misses-partial.csv")).expect("chart"),
        &SizeChartOptions::default(),
    )
    .expect("chart parses");
    let row = chart.rows.iter().find(|r| r.size == "8").expect("size 8");
    let mut g = c.benchmark_group("fit");
    g.sample_size(10);
    g.bench_function("fit_size_row_astm_8", |b| b.iter(|| fit_size(model, row, &FitOptions::default()).expect("fit")));
    g.finish();

    let dir = root.join("bodies");
    let mesh = read_mesh(&std::fs::read(dir.join("female-average-caucasian.glb")).expect("glb"), &Default::default())
        .expect("mesh");
    let lm =
        parse_landmarks(&std::fs::read_to_string(dir.join("female-average-caucasian.landmarks.json")).expect("lm"))
            .expect("landmarks");
    let scan = remesh_unrelated(&mesh, 60_000, &SimplifyOptions::default()).expect("remesh");
    let mut g = c.benchmark_group("derive_features");
    g.sample_size(10);
    g.bench_function("mannequin_27k", |b| {
        b.iter(|| derive_features(mesh.clone(), &lm, &DeriveOptions::default()).expect("derive"))
    });
    g.bench_function("scan_60k", |b| {
        b.iter(|| derive_features(scan.clone(), &lm, &DeriveOptions::default()).expect("derive"))
    });
    g.finish();

    // issue #17: a scan-like population body (re-meshed to 60k triangles, 1 mm noise)
    let body = &sample_population(40, 13)[1];
    let like = scan_like(&model.build(&body.params).expect("body"), 60_000, 1e-3, 13).expect("scan");
    let soup: Vec<[u64; 3]> = like.triangles().iter().map(|t| t.map(|v| u64::from(v.0))).collect();
    let mut g = c.benchmark_group("scan_as_it_comes");
    g.sample_size(10);
    g.bench_function("repair_and_frame_60k", |b| {
        b.iter(|| {
            let (mesh, _) = repair(like.positions(), &soup, &RepairOptions::default()).expect("repair");
            body_frame(&mesh, &FrameHints::default(), &FrameOptions::default()).expect("frame")
        })
    });
    g.bench_function("register_60k", |b| {
        b.iter(|| register(model, &like, &[], &RegisterOptions::default()).expect("register"))
    });
    g.finish();
}

criterion_group!(bodies, benches);
criterion_main!(bodies);
