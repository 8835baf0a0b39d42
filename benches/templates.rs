//! Garment template benchmarks (issue #3): encode and decode a template,
//! simplify MakeHuman's helper-skirt to a template's topology.
//! Run: `cargo bench --bench templates`.
#![expect(missing_docs, reason = "criterion_group! generates undocumented items")]

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::DVec3;
use grade3d::geom::mesh::VertexId;
use grade3d::geom::simplify::SimplifyOptions;
use grade3d::io::gltf::read_mesh;
use grade3d::template::codec::decode;
use grade3d::template::format::Relocation;
use grade3d::template::library::{builtin, reference_body, straight_skirt, trousers, SkirtOptions, TrouserOptions};
use grade3d::template::topology::topology_by_simplification;

fn benches(c: &mut Criterion) {
    let body = reference_body().expect("reference body");
    let library = builtin().expect("library");
    let mut g = c.benchmark_group("template");
    g.bench_function("encode_straight_skirt", |b| {
        b.iter(|| straight_skirt(&body, &SkirtOptions::default()).expect("encode"))
    });
    g.bench_function("encode_trousers", |b| b.iter(|| trousers(&body, &TrouserOptions::default()).expect("encode")));
    for t in &library {
        g.bench_function(format!("decode_{}", t.name), |b| {
            b.iter(|| decode(t, &body, Relocation::Eq1Frame).expect("decode"))
        });
    }
    g.finish();

    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/garments");
    let skirt = read_mesh(&std::fs::read(root.join("helper-skirt.glb")).expect("glb"), &Default::default())
        .expect("mesh")
        .welded(1e-9)
        .expect("weld");
    let bb = skirt.aabb();
    let centre = bb.centre();
    let mut encoded: Vec<VertexId> = Vec::new();
    for level in [bb.max.y, 0.5 * (bb.min.y + bb.max.y), bb.min.y] {
        for k in 0..8 {
            let ang = std::f64::consts::TAU * k as f64 / 8.0;
            let dir = DVec3::new(ang.sin(), 0.0, ang.cos());
            let v = (0..skirt.vertex_count())
                .min_by(|&a, &b| {
                    let score = |v: usize| {
                        let p = skirt.positions()[v];
                        (p - centre).with_y(0.0).normalize().distance(dir) + (p.y - level).abs()
                    };
                    score(a).total_cmp(&score(b))
                })
                .expect("vertices");
            let v = VertexId(v as u32);
            if !encoded.contains(&v) {
                encoded.push(v);
            }
        }
    }
    let mut g = c.benchmark_group("topology");
    g.sample_size(20);
    g.bench_function("simplify_helper_skirt_to_template", |b| {
        b.iter(|| topology_by_simplification(&skirt, &encoded, &SimplifyOptions::default()).expect("simplify"))
    });
    g.finish();
}

criterion_group!(templates, benches);
criterion_main!(templates);
