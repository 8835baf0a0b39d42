//! Issue #13's population: bodies the fixtures lack, graded with every
//! library template, each body both as the hm08 mesh and as a scan-like copy
//! (re-meshed to an unrelated topology, 1 mm normal noise, landmarks given
//! as points only).
//!
//! Every body's darts start from its template's block, as a scan's do in
//! the service (`grade3d::service::blocks`; the template graded on its
//! reference body): carried where they hold, decided on the body where not.
//!
//! Two tests, which run side by side: the first [`CI_BODIES`] (the planted
//! extremes and two draws) and the other draws; all 40 bodies in CI
//! (about 190 s on two cores):
//!
//! ```sh
//! cargo test --release --test population -- --nocapture
//! ```
//!
//! Bars asserted on every grade: the deepest garment vertex (fixed ones
//! included) at most 1.0 mm inside the body by the exact winding-number
//! test; no garment triangle through a body triangle (exact
//! triangle–triangle test) except where the body's thighs press together
//! (`grade3d::body::contact`: no two-legged garment can pass between them
//! outside the body; those pairs are printed); a detected contact carries its
//! warning; seam mismatch ≤ 1 mm; no flipped triangle, no self-crossing sew
//! or cut line; the ease per declared girth within ±5 mm of the expected.
//! Issue #14's bars on every grade: internal lines (dart legs, girth lines)
//! simple and inside their piece; skirt and trouser pieces |E_s| ≤ 2 % and
//! p95 edge strain ≤ 4 % (the trouser backs, whose bar the garment's shape
//! does not allow — the cloth follows the gluteal fold, a saddle, and the
//! strain is along the warp, not the weave's shear; printed per template —
//! held to [`bars::STRAIN_P95_OPEN`]); on the hm08 meshes (mirror-symmetric bodies) every
//! template mirror pair cut as one piece and mirror images within 0.5 %
//! (area, width, height) and 0.5 mm (sew lines). A scan-like copy is not
//! symmetric (its re-meshing and noise differ left and right): its pairs'
//! differences are printed.

use std::collections::BTreeMap;
use std::time::Instant;

use grade3d::body::derive::{derive_features, DeriveOptions, Landmarks};
use grade3d::collide::cache::Obstacle;
use grade3d::collide::render::{RenderOptions, Renderer, RendererChoice};
use grade3d::collide::DepthRenderer;
use grade3d::geom::mesh::TriMesh;
use grade3d::geom::winding::{WindingOptions, WindingTree};
use grade3d::mannequin::landmarks::hm08_landmarks;
use grade3d::mannequin::model::BodyModel;
use grade3d::mannequin::population::{sample_population, scan_like};
use grade3d::pattern::garment::{DartPlan, DartSource};
use grade3d::pipeline::{block, grade_with_darts, GradeOptions};
use grade3d::template::from_garment::author_from_garment;
use grade3d::template::library::{builtin, reference_body};

#[path = "common/bars.rs"]
mod bars;
use bars::Bars;
#[path = "common/authored.rs"]
mod authored;

/// The population's seed (any fixed value; this one is the issue's number).
const SEED: u64 = 13;
/// Bodies in the population.
const COUNT: usize = 40;
/// Failures of the authored templates (issue #18) left open, each the start
/// of its failure line (the rest of their grades meet every bar but
/// strain, which is held to its ceiling): none. pop06's front, whose sew
/// line crossed itself where the hem centre rose 10 cm (its centre-front
/// hem nodes were tied to the knees by Eq. (1)), is fixed: every node below
/// the hip hangs from it; pop20's scan-like copy, where 36 garment–body
/// triangle pairs stayed crossed at the waist band, is fixed since found
/// darts are capped at two a piece, a mirrored pair counting two.
const OPEN_FAILURES: [&str; 0] = [];

/// Bodies of the first test (the planted extremes and two draws).
const CI_BODIES: usize = 12;
/// Faces of the scan-like copies.
const SCAN_FACES: usize = 60_000;
/// Normal noise of the scan-like copies, m.
const NOISE_M: f64 = 1e-3;
/// The bodies `range` of the population, each as (name, mesh, landmarks) in
/// both forms.
fn bodies(range: std::ops::Range<usize>) -> Vec<(String, TriMesh, Landmarks)> {
    let model = BodyModel::embedded().unwrap();
    let mut out = Vec::new();
    for (i, b) in sample_population(COUNT, SEED).into_iter().enumerate().skip(range.start).take(range.len()) {
        let mesh = model.build(&b.params).unwrap();
        let lm = hm08_landmarks(model, &mesh, &Default::default()).unwrap_or_else(|e| panic!("{}: {e:?}", b.name));
        let scan = scan_like(&mesh, SCAN_FACES, NOISE_M, SEED ^ i as u64).unwrap();
        let points_only = Landmarks { points: lm.points.clone(), curves: BTreeMap::new() };
        out.push((b.name.clone(), mesh, lm));
        out.push((format!("{}-scan", b.name), scan, points_only));
    }
    out
}

fn run(range: std::ops::Range<usize>) {
    let renderer = Renderer::new(RendererChoice::Auto).expect("a depth-map renderer (the one the service picks)");
    let mut library = builtin().unwrap();
    // each template's block, as the service makes it (`grade3d::service::blocks`): graded on the
    // body it is authored on, its darts decided there; every body's darts start from it, as a scan's do
    let reference = reference_body().unwrap();
    let obstacle_of = |body: &grade3d::body::feature::FeatureBody| Obstacle {
        maps: renderer.depth_maps(&body.mesh, &RenderOptions::default()).unwrap(),
        tree: WindingTree::new(&body.mesh, &WindingOptions::default()),
    };
    let reference_obstacle = obstacle_of(&reference);
    let mut blocks: Vec<DartPlan> = library
        .iter()
        .map(|t| block(t, &reference, Some(&reference_obstacle), &GradeOptions::default()).unwrap())
        .collect();
    // issue #18: the skirt authored from MakeHuman's helper on its design body
    let design = authored::design_body();
    let skirt = author_from_garment("helper-skirt", &[authored::garment("helper-skirt")], design, &Default::default())
        .unwrap()
        .template;
    blocks.push(block(&skirt, design, Some(&obstacle_of(design)), &GradeOptions::default()).unwrap());
    library.push(skirt);
    // grades whose found darts are their block's (the block held, or there was none to carry)
    let mut block_held = 0usize;
    let mut bars = Bars::default();
    bars.open_templates.push(("helper-skirt".into(), authored::SKIRT_STRAIN_CEILING));
    bars.open_templates.push(("a-line-skirt".into(), authored::A_LINE_STRAIN_CEILING));
    let mut failures: Vec<String> = Vec::new();
    let mut contacts: Vec<String> = Vec::new();
    let bodies = bodies(range);
    let bodies_in_range: Vec<String> = bodies.iter().map(|b| b.0.clone()).collect();
    for (name, mesh, lm) in bodies {
        let body = match derive_features(mesh, &lm, &DeriveOptions::default()) {
            Ok(b) => b,
            Err(e) => {
                failures.push(format!("{name}: {e}"));
                continue;
            }
        };
        if let Some(c) = &body.thigh_contact {
            contacts.push(format!(
                "{name}: {:.1} mm below the crotch, {:.0} mm front to back",
                c.depth_below_crotch_mm, c.length_mm
            ));
            if !body.warnings.iter().any(|w| w.code == "thighs-in-contact") {
                failures.push(format!("{name}: thigh contact without its warning"));
            }
        }
        let obstacle = obstacle_of(&body);
        for (t, block) in library.iter().zip(&blocks) {
            let darts = DartSource::Block(block);
            let g = match grade_with_darts(t, &body, Some(&obstacle), &name, &GradeOptions::default(), darts) {
                Ok(g) => g,
                Err(e) => {
                    failures.push(format!("{} on {name}: {e}", t.name));
                    continue;
                }
            };
            if g.pattern.dart_plan.found == block.found {
                block_held += 1;
            }
            bars.check(t, &body, &obstacle, &g, &name, name.ends_with("-scan"));
        }
    }
    eprintln!("{} grades; the darts of {block_held} are their block's", bars.grades);
    bars.report();
    eprintln!("bodies whose thighs press together: {}", contacts.len());
    for c in &contacts {
        eprintln!("  {c}");
    }
    failures.extend(bars.failures);
    // the known failures of the authored skirt (issue #18, open): printed, and
    // each must still occur (a fixed one is taken off the list); any other fails
    let (known, failures): (Vec<String>, Vec<String>) =
        failures.into_iter().partition(|f| OPEN_FAILURES.iter().any(|k| f.starts_with(k)));
    for k in OPEN_FAILURES.iter().filter(|k| bodies_in_range.iter().any(|b| k.contains(&format!(" on {b}:")))) {
        assert!(
            known.iter().any(|f| f.starts_with(k)),
            "open failure no longer occurs, take it off OPEN_FAILURES: {k}"
        );
    }
    eprintln!("open failures (issue #18): {}", known.len());
    for f in &known {
        eprintln!("  {f}");
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn population_subset_stays_outside_the_body() {
    let start = Instant::now();
    run(0..CI_BODIES);
    eprintln!("{:.1} s", start.elapsed().as_secs_f64());
}

#[test]
fn rest_of_the_population_stays_outside_the_body() {
    let start = Instant::now();
    run(CI_BODIES..COUNT);
    eprintln!("{:.1} s", start.elapsed().as_secs_f64());
}
