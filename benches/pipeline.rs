//! One grade end to end (issues #5 and #6): the straight skirt on the
//! reference body — decode, 3 levels with collision and the exact pass,
//! flattening and pieces, SVG and DXF exports — and each stage alone; the
//! garment's penetration figures (every vertex, crossing triangle pairs) are
//! printed once, and the exact triangle–triangle query is timed.
//! Run: `cargo bench --bench pipeline`.
#![expect(missing_docs, reason = "criterion_group! generates undocumented items")]

use criterion::{criterion_group, criterion_main, Criterion};
use grade3d::collide::cache::{Obstacle, ObstacleCache, ObstacleCacheOptions};
use grade3d::collide::render::{RenderOptions, Renderer, RendererChoice};
use grade3d::collide::DepthRenderer;
use grade3d::geom::intersect::intersecting_pairs;
use grade3d::geom::winding::{penetration_stats, WindingOptions, WindingTree};
use grade3d::pattern::export::{dxf, svg};
use grade3d::pattern::garment::{pattern, PatternOptions};
use grade3d::pipeline::{grade, GradeOptions};
use grade3d::service::work::{self, BodyInput, WorkContext, WorkOptions};
use grade3d::template::library::{builtin, reference_body};

fn benches(c: &mut Criterion) {
    let body = reference_body().expect("reference body");
    let t = builtin().expect("library").into_iter().next().expect("skirt");
    // the renderer the service picks here (the CPU rasteriser where wgpu's adapter is a CPU driver)
    let renderer = Renderer::new(RendererChoice::Auto).expect("a renderer");
    eprintln!("depth maps: {}", renderer.describe());
    let obstacle = Some(Obstacle {
        maps: renderer.depth_maps(&body.mesh, &RenderOptions::default()).expect("render"),
        tree: WindingTree::new(&body.mesh, &WindingOptions::default()),
    });
    let opts = GradeOptions::default();
    let graded = grade(&t, &body, obstacle.as_ref(), "reference", &opts).expect("grade");
    eprintln!("stage timings of one grade: {:?}", graded.timings);
    if let Some(ob) = &obstacle {
        // issue #13: every vertex by the exact test, and the triangle pairs crossing the body
        let pen = penetration_stats(&ob.tree, &graded.mesh.positions.raw);
        let s = graded.collision.surface;
        eprintln!(
            "outside the body: {} of {} vertices inside, deepest {:.3} mm; {} garment triangles, {} crossing \
             pairs before clearing, {} after; clearing {:.1} ms",
            pen.inside,
            pen.total,
            pen.deepest_m * 1e3,
            s.garment_triangles,
            s.pairs_before,
            s.pairs_after,
            graded.timings.clear_ms
        );
    }
    let mut g = c.benchmark_group("grade_skirt");
    g.sample_size(10);
    g.bench_function("decode_refine_pattern", |b| {
        b.iter(|| grade(&t, &body, obstacle.as_ref(), "reference", &opts).expect("grade"))
    });
    g.bench_function("pattern_only", |b| {
        b.iter(|| {
            pattern(
                &t,
                &graded.mesh.positions,
                &graded.mesh.triangles,
                &graded.lineage,
                "reference",
                &PatternOptions::default(),
            )
            .expect("pattern")
        })
    });
    if let Some(ob) = &obstacle {
        // the exact triangle–triangle test over the body's hierarchy, the judge of clearing
        g.bench_function("intersecting_pairs_exact", |b| {
            b.iter(|| intersecting_pairs(&ob.tree, &graded.mesh.positions, &graded.mesh.triangles))
        });
    }
    g.bench_function("exports_svg_dxf", |b| {
        b.iter(|| {
            let s = svg::pieces_svg(&graded.pattern.pieces, &Default::default());
            let d = dxf::pieces_dxf(&t.name, &graded.pattern.pieces, &Default::default()).expect("dxf");
            (s, d)
        })
    });
    // the scan flow as the service runs it for one request: read the GLB and
    // landmarks, derive the feature model, render the depth maps and build the
    // winding tree (scans are not cached), grade, write SVG, DXF, JSON, GLB
    // and the report
    {
        let ctx = WorkContext {
            renderer: Some(std::sync::Arc::new(renderer)),
            obstacles: std::sync::Arc::new(ObstacleCache::new(ObstacleCacheOptions::default())),
            blocks: Default::default(),
            design_bodies: grade3d::service::work::DesignBodyResolver::core(),
            opts: WorkOptions::default(),
        };
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/bodies");
        let glb = std::fs::read(root.join("female-average-caucasian.glb")).expect("fixture");
        let lm = std::fs::read_to_string(root.join("female-average-caucasian.landmarks.json")).expect("fixture");
        let input = BodyInput { name: "scan", glb: &glb, landmarks: Some(&lm), hints: Default::default() };
        let once = work::scan(&ctx, std::slice::from_ref(&t), &input).expect("scan flow");
        eprintln!("scan flow stage timings (ms): {:?}", once.timings);
        g.bench_function("scan_flow_request", |b| {
            b.iter(|| work::scan(&ctx, std::slice::from_ref(&t), &input).expect("scan flow"))
        });
    }
    g.finish();
}

criterion_group!(pipeline_benches, benches);
criterion_main!(pipeline_benches);
