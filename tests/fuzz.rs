//! Mutation fuzzing of every parser a request reaches (issue #16 item 6),
//! on stable Rust with no extra tooling: each parser is fed mutants of the
//! real fixtures (bit flips, random bytes, insertions, deletions,
//! duplicated and spliced ranges, truncations, and tokens its format
//! cares about: quotes, brackets, separators, numbers at the edges of
//! their ranges, `NaN`, GLB chunk headers), from a fixed seed, so a run is
//! reproducible. A parser may refuse an input — that is its job — but it
//! must not panic and must not take a second over one input.
//!
//! Parsers: GLB and glTF JSON (`io::gltf::read_mesh`), landmarks JSON
//! (`io::landmarks::parse_landmarks`), size charts as CSV and JSON
//! (`mannequin::size_chart::parse_text`), template documents
//! (`template::format::Template::from_json`), job documents
//! (`service::parse_job_spec` and `service::job_units`: the JSON, the
//! chart or bodies in it) and multipart scan uploads
//! (`service::read_scan_parts`), and both of those again through the
//! router (`service::app`: `POST /v1/jobs`, `POST /v1/grade/scan`).
//!
//! `GRADE3D_FUZZ_ITERATIONS` (default 50 000: a few seconds in CI) sets the mutants per parser;
//! the runs through the router get a tenth (each is a request through the
//! router and, for an accepted job, a durable write). A panicking input is written to
//! `target/fuzz-crashes/` and the test fails naming it: make it a
//! regression test with the literal input.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use grade3d::mannequin::population::SplitMix64;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

fn read(rel: &str) -> Vec<u8> {
    std::fs::read(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn iterations() -> usize {
    std::env::var("GRADE3D_FUZZ_ITERATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(50_000)
}

/// No input may take longer than this.
const SLOWEST_ALLOWED: Duration = Duration::from_secs(1);

/// Tokens worth inserting into any of the formats.
const TOKENS: &[&[u8]] = &[
    b"\"",
    b"{",
    b"}",
    b"[",
    b"]",
    b",",
    b":",
    b"\n",
    b"\r\n",
    b";",
    b"\t",
    b"null",
    b"true",
    b"-",
    b"0",
    b"-0",
    b"1e308",
    b"-1e308",
    b"1e-320",
    b"NaN",
    b"inf",
    b"18446744073709551615",
    b"4294967295",
    b"-2147483649",
    b"65535",
    b"\\u0000",
    b"\\ud800",
    b"\xff\xfe",
    b"\xc3\x28",
    b"glTF",
    b"JSON",
    b"BIN\0",
    b"\0\0\0\0",
    b"\xff\xff\xff\xff",
    b"\x7f\xff\xff\xff",
    b"data:application/octet-stream;base64,",
    b"====",
    b"--X\r\n",
    b"Content-Disposition: form-data; name=\"scan\"; filename=\"b.glb\"\r\n\r\n",
];

/// Stacked byte-level mutations of a seed.
struct Mutator(SplitMix64);

impl Mutator {
    fn below(&mut self, n: usize) -> usize {
        (self.0.next_u64() % n.max(1) as u64) as usize
    }

    fn mutate(&mut self, seeds: &[Vec<u8>]) -> Vec<u8> {
        let mut v = seeds[self.below(seeds.len())].clone();
        for _ in 0..1 + self.below(6) {
            let len = v.len();
            let at = self.below(len + 1);
            match self.below(9) {
                0 if len > 0 => {
                    let i = self.below(len);
                    v[i] ^= 1 << self.below(8);
                }
                1 if len > 0 => {
                    let i = self.below(len);
                    v[i] = self.0.next_u64() as u8;
                }
                2 => {
                    let n = 1 + self.below(16);
                    let bytes: Vec<u8> = (0..n).map(|_| self.0.next_u64() as u8).collect();
                    v.splice(at..at, bytes);
                }
                3 if len > 0 => {
                    let end = (at + 1 + self.below(64)).min(len);
                    v.drain(at.min(len - 1)..end);
                }
                4 if len > 0 => {
                    let start = self.below(len);
                    let end = (start + 1 + self.below(256)).min(len);
                    let copy = v[start..end].to_vec();
                    v.splice(at..at, copy);
                }
                5 => v.truncate(at),
                6 | 7 => {
                    let t = TOKENS[self.below(TOKENS.len())];
                    v.splice(at..at, t.iter().copied());
                }
                _ => {
                    // splice: the head of this one, the tail of another seed
                    let other = &seeds[self.below(seeds.len())];
                    let from = self.below(other.len() + 1);
                    v.truncate(at);
                    v.extend_from_slice(&other[from..]);
                }
            }
        }
        v
    }
}

/// What one parser's run found.
struct Run {
    inputs: usize,
    refused: usize,
    slowest: Duration,
    crashes: Vec<PathBuf>,
}

/// Feeds `n` mutants of `seeds` to `parse` (true: accepted), the seeds
/// themselves first.
fn fuzz(name: &str, seeds: &[Vec<u8>], n: usize, mut parse: impl FnMut(&[u8]) -> bool) -> Run {
    let mut m = Mutator(SplitMix64(0x6772_6164_6533 ^ name.len() as u64));
    let mut run = Run { inputs: 0, refused: 0, slowest: Duration::ZERO, crashes: Vec::new() };
    let dir = root().join("target/fuzz-crashes");
    for i in 0..seeds.len() + n {
        let input = if i < seeds.len() { seeds[i].clone() } else { m.mutate(seeds) };
        let start = Instant::now();
        let outcome = catch_unwind(AssertUnwindSafe(|| parse(&input)));
        run.slowest = run.slowest.max(start.elapsed());
        run.inputs += 1;
        match outcome {
            Ok(true) => {}
            Ok(false) => run.refused += 1,
            Err(_) => {
                let _ = std::fs::create_dir_all(&dir);
                let path = dir.join(format!("{name}-{i}.bin"));
                let _ = std::fs::write(&path, &input);
                run.crashes.push(path);
            }
        }
    }
    eprintln!(
        "fuzz {name}: {} inputs, {} refused, slowest {:.1} ms, {} panics",
        run.inputs,
        run.refused,
        run.slowest.as_secs_f64() * 1e3,
        run.crashes.len()
    );
    run
}

fn check(run: &Run, name: &str) {
    assert!(run.crashes.is_empty(), "{name}: inputs that panic: {:?}", run.crashes);
    assert!(run.slowest <= SLOWEST_ALLOWED, "{name}: an input took {:?}", run.slowest);
}

fn text(bytes: &[u8]) -> String {
    // the service refuses a body that is not UTF-8 before any parser sees it
    String::from_utf8_lossy(bytes).into_owned()
}

#[test]
fn glb_and_gltf_readers_refuse_without_panicking() {
    use grade3d::geom::mesh::TriMesh;
    use grade3d::io::gltf::{read_mesh, write_glb};
    // small seeds keep each parse short: an icosahedron as GLB (binary chunk) and as glTF
    // JSON with its buffer in a data URI, and the head of a real scan
    let ico = TriMesh::icosahedron();
    let glb = write_glb(&ico, None, &[], "fuzz").unwrap();
    let json_len = u32::from_le_bytes([glb[12], glb[13], glb[14], glb[15]]) as usize;
    let bin = &glb[20 + json_len + 8..];
    use base64::Engine;
    let uri = format!("data:application/octet-stream;base64,{}", base64::engine::general_purpose::STANDARD.encode(bin));
    let mut doc: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    doc["buffers"][0]["uri"] = serde_json::Value::String(uri);
    let gltf = serde_json::to_vec(&doc).unwrap();
    let seeds = vec![glb, gltf];
    let n = iterations();
    let run = fuzz("gltf", &seeds, n, |b| read_mesh(b, &Default::default()).is_ok());
    check(&run, "gltf");
    assert!(run.refused < run.inputs, "the seeds parse");
}

#[test]
fn landmark_documents_refuse_without_panicking() {
    use grade3d::io::landmarks::parse_landmarks;
    let seeds = vec![
        read("fixtures/bodies/female-average-caucasian.landmarks.json"),
        read("fixtures/bodies/male-muscular-mixed.landmarks.json"),
    ];
    let run = fuzz("landmarks", &seeds, iterations(), |b| parse_landmarks(&text(b)).is_ok());
    check(&run, "landmarks");
}

#[test]
fn size_charts_refuse_without_panicking() {
    use grade3d::mannequin::size_chart::{parse_text, SizeChartOptions};
    let seeds = [
        "fixtures/size-charts/astm-d5585-11-misses-partial.csv",
        "fixtures/size-charts/mens-36-46-in.csv",
        "fixtures/size-charts/womens-34-44-cm.csv",
        "fixtures/size-charts/retailer-smL-cm.json",
    ]
    .map(read)
    .to_vec();
    let opts = SizeChartOptions::default();
    let run = fuzz("size-chart", &seeds, iterations(), |b| parse_text(&text(b), &opts).is_ok());
    check(&run, "size-chart");
}

#[test]
fn template_documents_refuse_without_panicking() {
    use grade3d::template::format::Template;
    let seeds = vec![read("templates/garments/straight-skirt.json")];
    // a template parse includes its JSON Schema check: a tenth of the mutants
    let run = fuzz("template", &seeds, iterations() / 10, |b| Template::from_json(&text(b)).is_ok());
    check(&run, "template");
}

/// The seed of the multipart fuzzing: a scan upload with a small GLB.
fn scan_upload() -> Vec<u8> {
    let lm = read("fixtures/bodies/female-average-caucasian.landmarks.json");
    let glb = grade3d::io::gltf::write_glb(&grade3d::geom::mesh::TriMesh::icosahedron(), None, &[], "fuzz").unwrap();
    let mut body = Vec::new();
    for (name, file, data) in
        [("scan", Some("b.glb"), &glb[..]), ("landmarks", None, &lm[..]), ("template", None, b"trousers")]
    {
        body.extend_from_slice(b"--X\r\nContent-Disposition: form-data; name=\"");
        body.extend_from_slice(name.as_bytes());
        body.push(b'"');
        if let Some(f) = file {
            body.extend_from_slice(format!("; filename=\"{f}\"").as_bytes());
        }
        body.extend_from_slice(b"\r\n\r\n");
        body.extend_from_slice(data);
        body.extend_from_slice(b"\r\n");
    }
    body.extend_from_slice(b"--X--\r\n");
    body
}

#[test]
fn job_documents_refuse_without_panicking() {
    use grade3d::mannequin::size_chart::SizeChartOptions;
    use grade3d::service::{job_units, parse_job_spec};
    let seeds = vec![read("fixtures/jobs/astm-misses-skirt-trousers.json")];
    let run = fuzz("job-document", &seeds, iterations(), |b| {
        parse_job_spec(b).and_then(|spec| job_units(&spec, SizeChartOptions::default(), 64)).is_ok()
    });
    check(&run, "job-document");
}

#[test]
fn multipart_scan_uploads_refuse_without_panicking() {
    use axum::body::Body;
    use axum::http::Request;
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    let run = fuzz("multipart-parts", &[scan_upload()], iterations(), |b| {
        let req = Request::post("/v1/grade/scan")
            .header("content-type", "multipart/form-data; boundary=X")
            .body(Body::from(b.to_vec()))
            .unwrap();
        rt.block_on(grade3d::service::read_scan_parts(req, 64 << 20)).is_ok()
    });
    check(&run, "multipart-parts");
}

/// Requests through the router of a service with no GPU context (a flow
/// that gets that far answers 503 `not-ready`): every answer must be a
/// problem document or a success, never a panic (500 from the catch-panic
/// layer counts as one).
fn http_fuzz(name: &str, seeds: &[Vec<u8>], content_type: &'static str, path: &'static str) {
    use axum::body::Body;
    use axum::http::{Request, StatusCode};
    use tower::ServiceExt;
    let dir = std::env::temp_dir().join(format!("grade3d-fuzz-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let mut cfg = grade3d::service::ServiceConfig::with_data_dir(dir.clone());
    cfg.max_pending_jobs = usize::MAX;
    let state = grade3d::service::AppState::open(cfg).unwrap();
    let app = grade3d::service::app(state);
    let rt = tokio::runtime::Builder::new_current_thread().enable_all().build().unwrap();
    let mut statuses = std::collections::BTreeMap::new();
    let run = fuzz(name, seeds, iterations() / 10, |b| {
        let req = Request::post(path).header("content-type", content_type).body(Body::from(b.to_vec())).unwrap();
        let resp = rt.block_on(app.clone().oneshot(req)).unwrap();
        assert_ne!(resp.status(), StatusCode::INTERNAL_SERVER_ERROR, "a 500 for a client's input");
        *statuses.entry(resp.status().as_u16()).or_insert(0usize) += 1;
        resp.status().is_success()
    });
    eprintln!("fuzz {name}: statuses {statuses:?}");
    let _ = std::fs::remove_dir_all(dir);
    check(&run, name);
}

#[test]
fn job_documents_through_the_router_refuse_without_panicking() {
    let seeds = vec![read("fixtures/jobs/astm-misses-skirt-trousers.json")];
    http_fuzz("job", &seeds, "application/json", "/v1/jobs");
}

#[test]
fn multipart_scan_uploads_through_the_router_refuse_without_panicking() {
    http_fuzz("multipart", &[scan_upload()], "multipart/form-data; boundary=X", "/v1/grade/scan");
}
