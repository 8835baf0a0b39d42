//! Garment template benchmarks (issue #3): encode and decode a template,
//! simplify MakeHuman's helper-skirt to a template's topology.
//! Run: `cargo bench --bench templates`.
#![expect(missing_docs, reason = "criterion_group! generates undocumented items")]

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use grade3d::geom::simplify::SimplifyOptions;
use grade3d::io::gltf::read_mesh;
use grade3d::template::codec::decode;
use grade3d::template::format::Relocation;
use grade3d::template::library::{builtin, reference_body, straight_skirt, trousers, SkirtOptions, TrouserOptions};
use grade3d::template::topology::{encoded_rings, topology_by_simplification};

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
    let encoded = encoded_rings(&skirt, 3, 8);
    let mut g = c.benchmark_group("topology");
    g.sample_size(20);
    g.bench_function("simplify_helper_skirt_to_template", |b| {
        b.iter(|| topology_by_simplification(&skirt, &encoded, &SimplifyOptions::default()).expect("simplify"))
    });
    g.finish();
}

criterion_group!(templates, benches);
criterion_main!(templates);
