//! The HTTP shell (axum). Handlers extract, check limits, run the work on
//! the bounded pool ([`pool`]) within their tracing span, map errors
//! ([`errors`]) and serialise; the flows themselves are plain functions
//! ([`work`]). [`app`] builds the router and is testable with `oneshot`.
//!
//! Routes (every one is registered through [`routes`], which also makes
//! the OpenAPI document: [`api`], committed as `openapi.yaml`):
//! - `GET /healthz`, `GET /readyz`, `GET /metrics`
//! - `GET|POST /v1/templates`, `GET|PUT|DELETE /v1/templates/{name}`
//! - `POST /v1/templates/from-garment`, `POST /v1/templates/from-curves`, `POST /v1/templates/{name}/edits` (sketch edits)
//! - `POST /v1/grade/size-chart` (JSON or CSV), `POST /v1/grade/scan` (multipart)
//! - `GET /v1/results/{id}`, `GET /v1/results/{id}/{artefact}`
//! - `POST /v1/jobs`, `GET /v1/jobs/{id}`, `GET /v1/jobs/{id}/artefacts/{artefact}`
//!
//! The `grade3d-service` crate (issue #16): it depends on the pure core,
//! the input parsers (`grade3d-io`) and the wgpu renderer
//! (`grade3d-render`); the core's modules are named here as `crate::geom`
//! and the like, as they were when this was one crate.

use grade3d_core::body::frame::FrameHints;
use grade3d_core::{body, geom, mannequin, pattern, pipeline, refine, template};
use grade3d_io as io;

pub mod api;
pub mod author;
pub mod blocks;
pub mod collide;
pub mod edit;

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};
use std::time::{Duration, Instant};

use axum::body::Bytes;
use axum::extract::{FromRequest, MatchedPath, Multipart, Path, Query, Request, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::{Json, Router};
use base64::Engine;
use utoipa_axum::router::OpenApiRouter;
use utoipa_axum::routes;

use crate::api::{
    ArtefactLink, GradeResult, JobProgress, JobView, Ready, SizeChartQuery, SizeChartRequest, VersionQuery,
};
use crate::collide::cache::{ObstacleCache, ObstacleCacheOptions};
use crate::collide::render::{Renderer, RendererChoice};
use crate::mannequin::size_chart::{parse_csv, parse_json, FigureType, SizeChart, SizeChartOptions};
use crate::pattern::export::rul::Created;
use crate::template::format::Template;

pub mod errors;
pub mod jobs;
pub mod metrics;
pub mod pool;
pub mod problem;
pub mod report;
pub mod results;
pub mod store;
pub mod work;

use jobs::{ArtefactEntry, JobRecord, JobSpec, JobState, JobStore};
use metrics::Metrics;
use pool::{PoolOptions, WorkPool};
use problem::Problem;
use results::{content_id, ResultCache, Stored};
use store::TemplateStore;
use work::{Artefact, BodyInput, Outcome, WorkContext, WorkOptions};

/// The service's configuration: flags of `grade3d serve`, each also read
/// from the environment variable named.
#[derive(Debug, Clone, clap::Args)]
pub struct ServiceConfig {
    /// Address to listen on.
    #[arg(long, env = "GRADE3D_ADDR", default_value = "127.0.0.1:8080")]
    pub addr: std::net::SocketAddr,
    /// Folder of the template store and the job database.
    #[arg(long, env = "GRADE3D_DATA_DIR", default_value = "grade3d-data")]
    pub data_dir: PathBuf,
    /// Bearer token that writes (template create/replace/delete) require;
    /// without one, writes are refused.
    #[arg(long, env = "GRADE3D_API_KEY", hide_env_values = true)]
    pub api_key: Option<String>,
    /// Require the API key for reads too.
    #[arg(long, env = "GRADE3D_PROTECT_READS", default_value_t = false)]
    pub protect_reads: bool,
    /// Largest request body, bytes.
    #[arg(long, env = "GRADE3D_MAX_BODY_BYTES", default_value_t = 64 << 20)]
    pub max_body_bytes: usize,
    /// Most vertices of a body scan.
    #[arg(long, env = "GRADE3D_MAX_SCAN_VERTICES", default_value_t = 500_000)]
    pub max_scan_vertices: usize,
    /// Most sizes per size chart.
    #[arg(long, env = "GRADE3D_MAX_SIZES", default_value_t = 40)]
    pub max_sizes: usize,
    /// Most templates per request.
    #[arg(long, env = "GRADE3D_MAX_TEMPLATES", default_value_t = 8)]
    pub max_templates: usize,
    /// Most bodies per batch job.
    #[arg(long, env = "GRADE3D_MAX_JOB_BODIES", default_value_t = 64)]
    pub max_job_bodies: usize,
    /// Work items running at once (default: the number of CPUs).
    #[arg(long, env = "GRADE3D_WORKERS")]
    pub workers: Option<usize>,
    /// Work items waiting beyond those before 503.
    #[arg(long, env = "GRADE3D_QUEUE_DEPTH", default_value_t = 16)]
    pub queue_depth: usize,
    /// Jobs queued or running before 503.
    #[arg(long, env = "GRADE3D_MAX_PENDING_JOBS", default_value_t = 64)]
    pub max_pending_jobs: usize,
    /// Time limit of a synchronous request, seconds (fractions allowed; > 0).
    #[arg(long, env = "GRADE3D_REQUEST_TIMEOUT_S", default_value_t = DEFAULT_REQUEST_TIMEOUT_S, value_parser = positive_seconds)]
    pub request_timeout_s: f64,
    /// How long the results of a scan are kept, seconds (0: not past the
    /// response that carries them).
    #[arg(long, env = "GRADE3D_SCAN_TTL_S", default_value_t = 600)]
    pub scan_ttl_s: u64,
    /// Memory for cached results, bytes.
    #[arg(long, env = "GRADE3D_RESULT_CACHE_BYTES", default_value_t = 256 << 20)]
    pub result_cache_bytes: usize,
    /// Grade without depth maps (no collision avoidance): for tests.
    #[arg(long, env = "GRADE3D_NO_GPU", default_value_t = false)]
    pub no_gpu: bool,
    /// What draws the body's depth maps: `auto` (wgpu on a GPU, the CPU
    /// rasteriser where wgpu's adapter is a CPU driver or there is none),
    /// `wgpu` or `cpu`.
    #[arg(long, env = "GRADE3D_RENDERER", default_value_t = RendererChoice::Auto)]
    pub renderer: RendererChoice,
}

/// `--request-timeout-s`'s default, seconds.
const DEFAULT_REQUEST_TIMEOUT_S: f64 = 120.0;

/// A time limit in seconds: finite and above 0.
fn positive_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= 1e9 => Ok(v),
        _ => Err(format!("`{text}` is not a number of seconds above 0")),
    }
}

impl ServiceConfig {
    /// The time limit of a synchronous request.
    pub fn request_timeout(&self) -> Duration {
        // the flag's parser keeps it finite and positive; a value set in code that is not
        // falls back to the default
        Duration::try_from_secs_f64(self.request_timeout_s)
            .unwrap_or_else(|_| Duration::from_secs_f64(DEFAULT_REQUEST_TIMEOUT_S))
    }

    /// The defaults of `grade3d serve` with `data_dir`.
    pub fn with_data_dir(data_dir: PathBuf) -> Self {
        use clap::Parser;
        #[derive(clap::Parser)]
        struct Wrap {
            #[command(flatten)]
            c: ServiceConfig,
        }
        let mut c = Wrap::parse_from(["grade3d"]).c;
        c.data_dir = data_dir;
        c
    }
}

/// What the service holds.
#[derive(Debug)]
pub struct Inner {
    /// Configuration.
    pub cfg: ServiceConfig,
    /// The template library.
    pub store: TemplateStore,
    /// Batch jobs.
    pub jobs: JobStore,
    /// The depth-map renderer, once its start-up has ended (`None` inside:
    /// not wanted, or wgpu asked for and not found).
    pub renderer: OnceLock<Option<Arc<Renderer>>>,
    /// Mannequin depth maps and winding trees.
    pub obstacles: Arc<ObstacleCache>,
    /// The templates' blocks ([`blocks`]), made as the service starts.
    pub blocks: Arc<blocks::BlockCache>,
    /// Design bodies from charts and stored scans ([`edit::design_body`]).
    pub design_bodies: edit::DesignBodies,
    /// Synchronous results.
    pub results: ResultCache,
    /// The bounded pool.
    pub pool: WorkPool,
    /// Metrics.
    pub metrics: Metrics,
    /// Jobs queued or running (admission: [`ServiceConfig::max_pending_jobs`];
    /// issue #16: it read the Prometheus gauges, and two submissions could
    /// both pass the check).
    pending_jobs: std::sync::atomic::AtomicUsize,
    /// Job progress (stage, done, total) of running jobs, in memory.
    pub progress: std::sync::Mutex<std::collections::HashMap<String, (String, usize, usize)>>,
    /// The job worker's queue.
    job_tx: tokio::sync::mpsc::UnboundedSender<String>,
    job_rx: std::sync::Mutex<Option<tokio::sync::mpsc::UnboundedReceiver<String>>>,
}

/// Shared state of the service (cheap to clone).
#[derive(Debug, Clone)]
pub struct AppState(pub Arc<Inner>);

impl AppState {
    /// Opens the stores under `cfg.data_dir` (seeding the built-in
    /// templates on first start) and queues again every unfinished job.
    /// The renderer is not opened: call [`AppState::start_gpu`].
    ///
    /// # Errors
    /// A message naming what failed.
    pub fn open(cfg: ServiceConfig) -> Result<Self, String> {
        let builtins =
            crate::template::library::builtin().map_err(|(name, e)| format!("built-in template `{name}`: {e}"))?;
        let store = TemplateStore::open(&cfg.data_dir.join("templates.redb"), &builtins).map_err(|e| e.to_string())?;
        let jobs = JobStore::open(&cfg.data_dir.join("jobs.redb")).map_err(|e| e.to_string())?;
        let pool = WorkPool::new(PoolOptions {
            workers: cfg.workers.unwrap_or_else(|| PoolOptions::default().workers),
            queue_depth: cfg.queue_depth,
            ..PoolOptions::default()
        });
        let (job_tx, job_rx) = tokio::sync::mpsc::unbounded_channel();
        let inner = Inner {
            results: ResultCache::new(cfg.result_cache_bytes),
            cfg,
            store,
            jobs,
            renderer: OnceLock::new(),
            obstacles: Arc::new(ObstacleCache::new(ObstacleCacheOptions::default())),
            blocks: Default::default(),
            design_bodies: Default::default(),
            pool,
            metrics: Metrics::new(),
            pending_jobs: Default::default(),
            progress: Default::default(),
            job_tx,
            job_rx: std::sync::Mutex::new(Some(job_rx)),
        };
        let state = Self(Arc::new(inner));
        for r in state.0.jobs.all().map_err(|e| e.to_string())? {
            state.0.metrics.jobs.with_label_values(&[r.state.as_str()]).inc();
            if matches!(r.state, JobState::Queued | JobState::Running) {
                state.0.pending_jobs.fetch_add(1, std::sync::atomic::Ordering::AcqRel);
                let _ = state.0.job_tx.send(r.id);
            }
        }
        Ok(state)
    }

    /// Opens the depth-map renderer on a blocking thread (or records that
    /// there is none); `/readyz` answers 200 once this has ended.
    pub fn start_gpu(&self) {
        let me = self.clone();
        std::thread::spawn(move || {
            let renderer = if me.0.cfg.no_gpu {
                None
            } else {
                match Renderer::new(me.0.cfg.renderer) {
                    Ok(r) => {
                        tracing::info!(renderer = %r.describe(), "depth-map renderer ready");
                        Some(Arc::new(r))
                    }
                    Err(e) => {
                        tracing::warn!(error = %e, "no wgpu adapter: grading runs without collision avoidance");
                        None
                    }
                }
            };
            let _ = me.0.renderer.set(renderer);
            // the live templates' blocks, made now rather than by their first scan (a scan that
            // comes first waits for the same build)
            let templates: Vec<Template> = me.0.store.live().unwrap_or_else(|e| {
                tracing::warn!(error = %e, "no blocks made at start: the live templates could not be read");
                Vec::new()
            });
            if let Ok(ctx) = me.work_context() {
                let start = std::time::Instant::now();
                let made = ctx.blocks(&templates).iter().filter(|b| b.is_some()).count();
                tracing::info!(templates = templates.len(), made, ms = start.elapsed().as_millis(), "blocks made");
            }
        });
    }

    /// Starts the job worker and the sweeper of expired scan results (call
    /// once, inside the tokio runtime).
    pub fn start_background(&self) {
        let rx = self.0.job_rx.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(mut rx) = rx {
            let me = self.clone();
            tokio::spawn(async move {
                while let Some(id) = rx.recv().await {
                    let me2 = me.clone();
                    let span = tracing::info_span!("job", %id);
                    let _ = tokio::task::spawn_blocking(move || span.in_scope(|| run_job(&me2, &id))).await;
                }
            });
        }
        let me = self.clone();
        tokio::spawn(async move {
            let mut tick = tokio::time::interval(Duration::from_secs(5));
            loop {
                tick.tick().await;
                let n = me.0.results.purge_expired();
                if n > 0 {
                    tracing::info!(purged = n, "expired scan results forgotten");
                }
            }
        });
    }

    fn work_context(&self) -> Result<WorkContext, Problem> {
        let renderer = self.0.renderer.get().ok_or_else(not_ready)?.clone();
        Ok(WorkContext {
            renderer,
            obstacles: Arc::clone(&self.0.obstacles),
            blocks: Arc::clone(&self.0.blocks),
            design_bodies: {
                let me = self.clone();
                work::DesignBodyResolver(Arc::new(move |which| {
                    edit::design_body(&me, which).map_err(|p| format!("{}: {}", p.kind, p.detail))
                }))
            },
            opts: WorkOptions { max_scan_vertices: self.0.cfg.max_scan_vertices, ..WorkOptions::default() },
        })
    }

    fn chart_options(&self) -> SizeChartOptions {
        SizeChartOptions { max_sizes: self.0.cfg.max_sizes, ..SizeChartOptions::default() }
    }
}

fn not_ready() -> Problem {
    let mut p = Problem::new(StatusCode::SERVICE_UNAVAILABLE, "not-ready", "Not ready", "the GPU context is starting");
    p.retry_after_s = Some(1);
    p
}

/// Every route with its OpenAPI operation: the one list both the router
/// ([`app`]) and the contract ([`api::openapi`]) are made from.
pub fn routes() -> OpenApiRouter<AppState> {
    OpenApiRouter::with_openapi(<api::ApiDoc as utoipa::OpenApi>::openapi())
        .routes(routes!(healthz))
        .routes(routes!(readyz))
        .routes(routes!(metrics_text))
        .routes(routes!(get_vocabulary))
        .routes(routes!(list_templates, create_template))
        .routes(routes!(get_template, replace_template, delete_template))
        .routes(routes!(create_template_from_garment))
        .routes(routes!(create_template_from_curves))
        .routes(routes!(edit_template))
        .routes(routes!(grade_size_chart))
        .routes(routes!(grade_scan))
        .routes(routes!(get_result))
        .routes(routes!(get_result_artefact))
        .routes(routes!(submit_job))
        .routes(routes!(get_job))
        .routes(routes!(get_job_artefact))
}

/// The service's router: [`routes`] with the fallbacks and the layers.
pub fn app(state: AppState) -> Router {
    let (router, _) = routes().split_for_parts();
    router
        .fallback(|| async { Problem::not_found("no such route") })
        .method_not_allowed_fallback(|| async {
            Problem::new(StatusCode::METHOD_NOT_ALLOWED, "method-not-allowed", "Method not allowed", "see openapi.yaml")
        })
        .layer(axum::extract::DefaultBodyLimit::disable())
        .layer(middleware::from_fn_with_state(state.clone(), observe))
        .layer(tower_http::catch_panic::CatchPanicLayer::custom(|_| {
            tracing::error!("handler panicked");
            Problem::internal().into_response()
        }))
        // one line per request at INFO (method, path, status, latency), in the request's span
        .layer(
            tower_http::trace::TraceLayer::new_for_http()
                .make_span_with(tower_http::trace::DefaultMakeSpan::new().level(tracing::Level::INFO))
                .on_response(
                    tower_http::trace::DefaultOnResponse::new()
                        .level(tracing::Level::INFO)
                        .latency_unit(tower_http::LatencyUnit::Millis),
                ),
        )
        .with_state(state)
}

/// Records every request in the metrics, by route template (never by the
/// raw path, which could carry ids).
async fn observe(State(s): State<AppState>, req: Request, next: Next) -> Response {
    let route = req.extensions().get::<MatchedPath>().map_or("unmatched", |m| m.as_str()).to_owned();
    let method = req.method().clone();
    let start = Instant::now();
    let resp = next.run(req).await;
    let m = &s.0.metrics;
    m.requests.with_label_values(&[route.as_str(), method.as_str(), resp.status().as_str()]).inc();
    m.latency.with_label_values(&[route.as_str()]).observe(start.elapsed().as_secs_f64());
    resp
}

/// Liveness: the process answers.
#[utoipa::path(get, path = "/healthz", tag = "operations", operation_id = "healthz",
    responses((status = 200, description = "The process answers.", body = String, content_type = "text/plain", example = "ok")))]
async fn healthz() -> &'static str {
    "ok"
}

/// Readiness: the wgpu adapter's start-up ended and the template library is loaded.
#[utoipa::path(get, path = "/readyz", tag = "operations", operation_id = "readyz",
    responses(
        (status = 200, description = "Ready.", body = Ready),
        (status = 503, response = api::Unavailable),
        (status = 500, response = api::Internal),
    ))]
async fn readyz(State(s): State<AppState>) -> Result<Json<Ready>, Problem> {
    let renderer = s.0.renderer.get().ok_or_else(not_ready)?;
    let me = s.clone();
    let templates = off_executor(move || Ok(me.0.store.list()?.len())).await?;
    Ok(Json(Ready { ready: true, templates, gpu: renderer.as_ref().map(|r| r.describe()) }))
}

/// Prometheus metrics (text exposition format 0.0.4).
///
/// Requests, latency histograms, stage times, queue depth, cache lookups, jobs.
#[utoipa::path(get, path = "/metrics", tag = "operations", operation_id = "metrics",
    responses((status = 200, description = "The metrics.", body = String, content_type = "text/plain")))]
async fn metrics_text(State(s): State<AppState>) -> Response {
    let m = &s.0.metrics;
    m.queue_depth.set(s.0.pool.depth() as i64);
    let (hits, misses) = (s.0.obstacles.hits(), s.0.obstacles.misses());
    let c = m.cache.with_label_values(&["obstacles", "hit"]);
    c.inc_by(hits.saturating_sub(c.get()));
    let c = m.cache.with_label_values(&["obstacles", "miss"]);
    c.inc_by(misses.saturating_sub(c.get()));
    ([(header::CONTENT_TYPE, "text/plain; version=0.0.4; charset=utf-8")], m.render()).into_response()
}

// --- limits, authentication, parsing -------------------------------------------------------

/// The request body, at most `max_body_bytes`: a declared `Content-Length`
/// past the limit is refused before any of the body is read.
async fn body_bytes(s: &AppState, headers: &HeaderMap, body: axum::body::Body) -> Result<Bytes, Problem> {
    let max = s.0.cfg.max_body_bytes;
    let declared =
        headers.get(header::CONTENT_LENGTH).and_then(|v| v.to_str().ok()).and_then(|v| v.parse::<u64>().ok());
    if declared.is_some_and(|n| n > max as u64) {
        return Err(too_large(max));
    }
    axum::body::to_bytes(body, max).await.map_err(|_| too_large(max))
}

fn utf8(bytes: Bytes) -> Result<String, Problem> {
    String::from_utf8(bytes.to_vec()).map_err(|_| Problem::bad_request("not-utf8", "the body is not UTF-8"))
}

fn too_large(max: usize) -> Problem {
    Problem::new(
        StatusCode::PAYLOAD_TOO_LARGE,
        "body-too-large",
        "Request body too large",
        format!("the request body exceeds {max} bytes"),
    )
}

/// Whether `given` is `key`, in constant time: both hashed (BLAKE3, so
/// the comparison takes as long whatever their lengths) and the digests
/// compared with `subtle` (issue #16: a hand-written fold the optimiser
/// was free to cut short).
fn keys_match(given: &str, key: &str) -> bool {
    use subtle::ConstantTimeEq;
    let (a, b) = (blake3::hash(given.as_bytes()), blake3::hash(key.as_bytes()));
    a.as_bytes().ct_eq(b.as_bytes()).into()
}

fn check_key(s: &AppState, headers: &HeaderMap, write: bool) -> Result<(), Problem> {
    if !write && !s.0.cfg.protect_reads {
        return Ok(());
    }
    let Some(key) = &s.0.cfg.api_key else {
        return Err(Problem::new(
            StatusCode::FORBIDDEN,
            "writes-disabled",
            "Writes disabled",
            "this server has no API key configured (GRADE3D_API_KEY), so it accepts no writes",
        ));
    };
    let given = headers
        .get(header::AUTHORIZATION)
        .and_then(|v| v.to_str().ok())
        .and_then(|v| v.strip_prefix("Bearer "))
        .ok_or_else(|| Problem::unauthorized("an `Authorization: Bearer <API key>` header is required"))?;
    if keys_match(given, key) {
        Ok(())
    } else {
        Err(Problem::unauthorized("the API key is not valid"))
    }
}

fn parse_json_body<T: serde::de::DeserializeOwned>(bytes: &[u8]) -> Result<T, Problem> {
    let de = &mut serde_json::Deserializer::from_slice(bytes);
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = e.path().to_string();
        let field = if path == "." { "body".to_owned() } else { format!("body.{path}") };
        Problem::bad_request("invalid-json", e.inner().to_string()).field(field)
    })
}

fn valid_name(name: &str) -> Result<(), Problem> {
    let ok = !name.is_empty()
        && name.len() <= 64
        && name.bytes().all(|b| b.is_ascii_alphanumeric() || b == b'-' || b == b'_' || b == b'.');
    if ok {
        Ok(())
    } else {
        Err(Problem::bad_request("invalid-name", "names are 1–64 characters of A–Z a–z 0–9 - _ .").field("name"))
    }
}

/// Runs `f` (a call into the redb stores: reads, and writes that fsync; a
/// template's parse and schema check) on tokio's blocking threads within
/// the request's tracing span, so that no executor thread waits on the disk
/// (issue #16: they ran on the executor). Not the work pool: a template
/// read is never refused because grades fill its queue.
async fn off_executor<T: Send + 'static>(
    f: impl FnOnce() -> Result<T, Problem> + Send + 'static,
) -> Result<T, Problem> {
    let span = tracing::Span::current();
    tokio::task::spawn_blocking(move || span.in_scope(f)).await.map_err(|e| {
        tracing::error!(error = %e, "store call panicked");
        Problem::internal()
    })?
}

/// The live templates named, in order (at most `max_templates`), read off
/// the executor.
async fn resolve_templates(
    s: &AppState,
    names: &[String],
    field: &str,
) -> Result<Vec<(u32, String, Template)>, Problem> {
    let (me, names, field) = (s.clone(), names.to_vec(), field.to_owned());
    off_executor(move || resolve_templates_now(&me, &names, &field)).await
}

/// [`resolve_templates`] on the calling thread.
fn resolve_templates_now(s: &AppState, names: &[String], field: &str) -> Result<Vec<(u32, String, Template)>, Problem> {
    if names.is_empty() {
        return Err(Problem::bad_request("no-templates", "name at least one template").field(field));
    }
    if names.len() > s.0.cfg.max_templates {
        return Err(Problem::bad_request(
            "too-many-templates",
            format!("{} templates named; at most {} per request", names.len(), s.0.cfg.max_templates),
        )
        .field(field));
    }
    let mut out = Vec::with_capacity(names.len());
    for (i, n) in names.iter().enumerate() {
        if names[..i].contains(n) {
            return Err(Problem::bad_request("duplicate-template", format!("template `{n}` named twice")).field(field));
        }
        let (v, json) = s.0.store.get_json(n, None).map_err(|e| match e {
            store::StoreError::NotFound { .. } => {
                Problem::unprocessable("unknown-template", e.to_string()).field(field)
            }
            other => Problem::from(other),
        })?;
        let t = Template::from_json(&json).map_err(|e| errors::template_problem(&e))?;
        out.push((v, json, t));
    }
    Ok(out)
}

// --- vocabulary ----------------------------------------------------------------------------

/// The feature vocabulary: every point and curve, the landmarks a scan must
/// give, and the live templates that place nodes on each point.
#[utoipa::path(get, path = "/v1/vocabulary", tag = "templates", operation_id = "getVocabulary",
    security((), ("apiKey" = [])),
    responses(
        (status = 200, description = "The vocabulary; landmarks documents follow the `Landmarks` schema.",
            body = api::Vocabulary),
        (status = 401, response = api::Unauthorized),
        (status = 403, response = api::Forbidden),
        (status = 500, response = api::Internal),
    ))]
async fn get_vocabulary(State(s): State<AppState>, headers: HeaderMap) -> Result<Json<api::Vocabulary>, Problem> {
    check_key(&s, &headers, false)?;
    let templates = off_executor(move || Ok(s.0.store.live()?)).await?;
    Ok(Json(vocabulary(&templates)))
}

/// The vocabulary document of [`get_vocabulary`] for `templates`.
fn vocabulary(templates: &[crate::template::format::Template]) -> api::Vocabulary {
    use crate::body::vocab::{CurveRule, PointId, CURVES, POINTS, VOCABULARY_VERSION};
    let landmarks = crate::body::vocab::required_landmarks();
    let ids = |points: &[PointId]| points.iter().map(|p| p.as_str().to_owned()).collect::<Vec<_>>();
    api::Vocabulary {
        version: VOCABULARY_VERSION,
        landmarks: ids(&landmarks),
        points: POINTS
            .iter()
            .map(|p| api::VocabularyPoint {
                id: p.id.as_str().to_owned(),
                name: p.name.to_owned(),
                landmark: landmarks.contains(&p.id),
                optional: crate::body::vocab::optional_point(p.id),
                curves: [p.f1.as_str().to_owned(), p.f2.as_str().to_owned()],
                templates: templates
                    .iter()
                    .filter(|t| t.nodes.iter().any(|n| n.point == p.id))
                    .map(|t| t.name.clone())
                    .collect(),
            })
            .collect(),
        curves: CURVES
            .iter()
            .map(|c| api::VocabularyCurve {
                id: c.id.as_str().to_owned(),
                name: c.name.to_owned(),
                landmarks: match c.rule {
                    CurveRule::Section { landmarks, .. } | CurveRule::Path { landmarks, .. } => ids(landmarks),
                },
                optional: crate::body::vocab::optional_curve(c.id),
            })
            .collect(),
    }
}

// --- templates -----------------------------------------------------------------------------

/// Live templates and their versions.
#[utoipa::path(get, path = "/v1/templates", tag = "templates", operation_id = "listTemplates",
    security((), ("apiKey" = [])),
    responses(
        (status = 200, description = "Every live template.", body = Vec<store::Entry>),
        (status = 401, response = api::Unauthorized),
        (status = 403, response = api::Forbidden),
        (status = 500, response = api::Internal),
    ))]
async fn list_templates(State(s): State<AppState>, headers: HeaderMap) -> Result<Json<Vec<store::Entry>>, Problem> {
    check_key(&s, &headers, false)?;
    Ok(Json(off_executor(move || Ok(s.0.store.list()?)).await?))
}

/// A template document: the live version, or `version`.
#[utoipa::path(get, path = "/v1/templates/{name}", tag = "templates", operation_id = "getTemplate",
    security((), ("apiKey" = [])),
    params(("name" = String, Path, description = "The template's name."), VersionQuery),
    responses(
        (status = 200, description = "The template document (its JSON Schema: `templates/schema/garment-template.schema.json`).",
            body = api::TemplateDocument, headers(("x-template-version" = String, description = "The version answered."))),
        (status = 400, response = api::BadRequest),
        api::ReadProblems,
    ))]
async fn get_template(
    State(s): State<AppState>,
    headers: HeaderMap,
    Path(name): Path<String>,
    q: Result<Query<VersionQuery>, axum::extract::rejection::QueryRejection>,
) -> Result<Response, Problem> {
    check_key(&s, &headers, false)?;
    let Query(q) = q.map_err(|e| Problem::bad_request("invalid-query", e.body_text()).field("version"))?;
    let me = s.clone();
    let (version, json) = off_executor(move || Ok(me.0.store.get_json(&name, q.version)?)).await?;
    let mut resp = ([(header::CONTENT_TYPE, "application/json")], json).into_response();
    if let Ok(v) = HeaderValue::from_str(&version.to_string()) {
        resp.headers_mut().insert("x-template-version", v);
    }
    Ok(resp)
}

/// Create a template (version 1).
#[utoipa::path(post, path = "/v1/templates", tag = "templates", operation_id = "createTemplate",
    security(("apiKey" = [])),
    request_body(content = api::TemplateDocument, content_type = "application/json",
        description = "A garment feature template document (`templates/schema/garment-template.schema.json`): nodes by Eq. (1) of Wang, Wang & Yuen, edges with profiles, faces, panels, seams, darts, notches, grain lines, defaults."),
    responses(
        (status = 201, description = "Created, durably.", body = store::Entry,
            headers(("Location" = String, description = "/v1/templates/{name}"))),
        (status = 409, response = api::Conflict),
        api::WriteProblems,
    ))]
async fn create_template(
    State(s): State<AppState>,
    headers: HeaderMap,
    body: axum::body::Body,
) -> Result<Response, Problem> {
    // the body is read before the key is checked: a refusal mid-upload would break the client's pipe
    let bytes = body_bytes(&s, &headers, body).await?;
    check_key(&s, &headers, true)?;
    let text = utf8(bytes)?;
    let me = s.clone();
    let limit = s.0.cfg.request_timeout();
    let entry = s.0.pool.run(limit, move || me.0.store.put(None, &text, true)).await??;
    let location = format!("/v1/templates/{}", entry.name);
    Ok((StatusCode::CREATED, [(header::LOCATION, location)], Json(entry)).into_response())
}

/// Author a template from a designed garment (issue #18) and store it as version 1.
#[utoipa::path(post, path = "/v1/templates/from-garment", tag = "templates", operation_id = "createTemplateFromGarment",
    security(("apiKey" = [])),
    request_body(content = author::GarmentUpload, content_type = "multipart/form-data",
        description = "A garment draped on its design body: pieces welded, seams found, tubes cut, girth lines and nodes picked, the surface contracted to them (seed 000 §3.3), profiles attached, nodes encoded by Eq. (1) or placed relative to the body's girths."),
    responses(
        (status = 201, description = "Authored and stored, durably; what could not be mapped is listed.", body = author::Authored,
            headers(("Location" = String, description = "/v1/templates/{name}"))),
        (status = 409, response = api::Conflict),
        api::FlowProblems,
    ))]
async fn create_template_from_garment(
    State(s): State<AppState>,
    headers: HeaderMap,
    req: Request,
) -> Result<Response, Problem> {
    if !media_is(&headers, "multipart/form-data") {
        return Err(unsupported_media(
            "multipart/form-data with parts garment and name, optionally body (or body_scan with \
             body_landmarks, up, facing; or body_chart with body_size), units, options",
        ));
    }
    let (parts, body) = req.into_parts();
    // the body is read before the key is checked: a refusal mid-upload would break the client's pipe
    let bytes = body_bytes(&s, &headers, body).await?;
    check_key(&s, &headers, true)?;
    let req = Request::from_parts(parts, axum::body::Body::from(bytes));
    let input = author::read_author_parts(req, s.0.cfg.max_body_bytes, s.chart_options()).await?;
    valid_name(&input.name)?;
    let me = s.clone();
    store_authored(&s, move || author::author(&me, &input)).await
}

/// Runs an authoring on the pool and stores its template as version 1: 201
/// with its `Location` and the authoring's report.
async fn store_authored(
    s: &AppState,
    run: impl FnOnce() -> Result<(Template, author::Authored), Problem> + Send + 'static,
) -> Result<Response, Problem> {
    let me = s.clone();
    let report =
        s.0.pool
            .run(s.0.cfg.request_timeout(), move || -> Result<author::Authored, Problem> {
                let (t, report) = run()?;
                let entry = me.0.store.put(None, &t.to_json(), true)?;
                Ok(author::Authored { template: entry, ..report })
            })
            .await??;
    let location = format!("/v1/templates/{}", report.template.name);
    Ok((StatusCode::CREATED, [(header::LOCATION, location)], Json(report)).into_response())
}

/// Author a template from 3D curves (issue #18 item 2, seed 001) and store it as version 1.
#[utoipa::path(post, path = "/v1/templates/from-curves", tag = "templates", operation_id = "createTemplateFromCurves",
    security(("apiKey" = [])),
    request_body(content = author::CurvesUpload, content_type = "application/json",
        description = "Panels as four 3D boundary curves each, drawn on their design body: each panel a Coons patch (seed 001's bicubically blended form), sampled, sewn to the others along shared curves, then authored as a designed garment (seed 000 §3.3)."),
    responses(
        (status = 201, description = "Authored and stored, durably; what could not be mapped is listed.", body = author::Authored,
            headers(("Location" = String, description = "/v1/templates/{name}"))),
        (status = 409, response = api::Conflict),
        api::FlowProblems,
    ))]
async fn create_template_from_curves(
    State(s): State<AppState>,
    headers: HeaderMap,
    body: axum::body::Body,
) -> Result<Response, Problem> {
    if !media_is(&headers, "application/json") {
        return Err(unsupported_media("application/json"));
    }
    let bytes = body_bytes(&s, &headers, body).await?;
    check_key(&s, &headers, true)?;
    let input: author::CurvesUpload = parse_json_body(&bytes)?;
    valid_name(&input.name)?;
    let (me, charts) = (s.clone(), s.chart_options());
    store_authored(&s, move || author::author_curves(&me, &input, &charts)).await
}

/// Replace a template (a new version; earlier versions stay readable).
#[utoipa::path(put, path = "/v1/templates/{name}", tag = "templates", operation_id = "replaceTemplate",
    security(("apiKey" = [])),
    params(("name" = String, Path, description = "The template's name.")),
    request_body(content = api::TemplateDocument, content_type = "application/json",
        description = "The new template document (`templates/schema/garment-template.schema.json`)."),
    responses(
        (status = 200, description = "The new live version, written durably.", body = store::Entry),
        (status = 404, response = api::NotFound),
        api::WriteProblems,
    ))]
async fn replace_template(
    State(s): State<AppState>,
    headers: HeaderMap,
    Path(name): Path<String>,
    body: axum::body::Body,
) -> Result<Json<store::Entry>, Problem> {
    let text = utf8(named_write(&s, &headers, &name, body).await?)?;
    let me = s.clone();
    let limit = s.0.cfg.request_timeout();
    Ok(Json(s.0.pool.run(limit, move || me.0.store.put(Some(&name), &text, false)).await??))
}

/// The body of a write to the template `name`: read within the limit (before
/// the key is checked: a refusal mid-upload would break the client's pipe),
/// the key checked, the name a valid one.
async fn named_write(s: &AppState, headers: &HeaderMap, name: &str, body: axum::body::Body) -> Result<Bytes, Problem> {
    let bytes = body_bytes(s, headers, body).await?;
    check_key(s, headers, true)?;
    valid_name(name)?;
    Ok(bytes)
}

/// Apply a sketch edit to a template (issue #18 items 3–4; seed 000 §4, seed 002) and store it as the next version.
#[utoipa::path(post, path = "/v1/templates/{name}/edits", tag = "templates", operation_id = "editTemplate",
    security(("apiKey" = [])),
    params(("name" = String, Path, description = "The template's name: its live version is edited.")),
    request_body(content = crate::template::edit::SketchEdit, content_type = "application/json",
        description = "A stroke in a canonical orthographic view (front, back, left, right; metres per pixel λ, the pixel of the world origin): `move_node` (a node and a direction stroke: Eq. (4), sign kept) or `profile` (a stroke re-profiling the visible edges within ε: Eqs. (6)–(7), the K(v) rules). Applied on the template's design body; moved nodes re-encoded by Eq. (1)."),
    responses(
        (status = 201, description = "Stored, durably, as the next version (the previous ones kept: undo is a PUT of an earlier version); what was resolved (mirrored edits) and the preview (coarse and refined garment GLB on the design body).",
            body = edit::TemplateEdited,
            headers(("Location" = String, description = "/v1/templates/{name}?version={version}"))),
        (status = 404, response = api::NotFound),
        (status = 409, response = api::Conflict),
        api::WriteProblems,
    ))]
async fn edit_template(
    State(s): State<AppState>,
    headers: HeaderMap,
    Path(name): Path<String>,
    body: axum::body::Body,
) -> Result<Response, Problem> {
    let request: crate::template::edit::SketchEdit = parse_json_body(&named_write(&s, &headers, &name, body).await?)?;
    let me = s.clone();
    let edited = s.0.pool.run(s.0.cfg.request_timeout(), move || edit::edit(&me, &name, &request)).await??;
    let location = format!("/v1/templates/{}?version={}", edited.report.template.name, edited.report.template.version);
    Ok((StatusCode::CREATED, [(header::LOCATION, location)], Json(edited)).into_response())
}

/// Delete a template (its versions stay readable by number).
#[utoipa::path(delete, path = "/v1/templates/{name}", tag = "templates", operation_id = "deleteTemplate",
    security(("apiKey" = [])),
    params(("name" = String, Path, description = "The template's name.")),
    responses(
        (status = 204, description = "Deleted."),
        api::ReadProblems,
    ))]
async fn delete_template(
    State(s): State<AppState>,
    headers: HeaderMap,
    Path(name): Path<String>,
) -> Result<StatusCode, Problem> {
    check_key(&s, &headers, true)?;
    off_executor(move || Ok(s.0.store.delete(&name)?)).await?;
    Ok(StatusCode::NO_CONTENT)
}

// --- the grading flows ---------------------------------------------------------------------

fn links(base: &str, artefacts: impl Iterator<Item = (String, String, usize)>) -> Vec<ArtefactLink> {
    artefacts
        .map(|(name, media_type, bytes)| ArtefactLink { href: format!("{base}/{name}"), name, media_type, bytes })
        .collect()
}

/// The answer of a flow whose outcome's report and timings are given
/// (moved, not copied) with its `artefacts`.
fn summary(
    id: &str,
    flow: report::Flow,
    report: serde_json::Value,
    timings_ms: std::collections::BTreeMap<String, f64>,
    artefacts: &[Artefact],
    expires_s: Option<u64>,
) -> GradeResult {
    let base = format!("/v1/results/{id}");
    GradeResult {
        id: id.to_owned(),
        flow,
        artefacts: links(&base, artefacts.iter().map(|a| (a.name.clone(), a.media_type.to_owned(), a.bytes.len()))),
        href: base,
        expires_in_s: expires_s,
        report,
        timings_ms,
        cached: false,
    }
}

fn answer(stored: &Stored, cached: bool) -> Response {
    Json(GradeResult { cached, ..stored.summary.clone() }).into_response()
}

/// Runs a flow on the pool, stores its outcome under `id` and answers it.
async fn run_flow(
    s: &AppState,
    id: String,
    flow: report::Flow,
    ttl: Option<Duration>,
    f: impl FnOnce(&WorkContext) -> Result<Outcome, work::WorkError> + Send + 'static,
) -> Result<Response, Problem> {
    if let Some(hit) = s.0.results.get(&id) {
        s.0.metrics.cache.with_label_values(&["results", "hit"]).inc();
        return Ok(answer(&hit, true));
    }
    s.0.metrics.cache.with_label_values(&["results", "miss"]).inc();
    let ctx = s.work_context()?;
    let limit = s.0.cfg.request_timeout();
    let outcome = s.0.pool.run(limit, move || f(&ctx)).await??;
    s.0.metrics.observe_stages(&outcome.timings);
    let expires = ttl.map(|t| Instant::now() + t);
    let Outcome { report, artefacts, timings } = outcome;
    let summary = summary(&id, flow, report, timings, &artefacts, ttl.map(|t| t.as_secs()));
    let stored = s.0.results.put(id, Stored { summary, artefacts, expires });
    Ok(answer(&stored, false))
}

/// The `.RUL` creation stamp of a flow: the request's `created` (RFC 3339),
/// read now so that a bad one is a 400 before any work; `None` when not
/// given (the flow is stamped when it runs, [`stamp_now`]).
fn parse_created(created: Option<&str>) -> Result<Option<Created>, Problem> {
    created.map(Created::from_rfc3339).transpose().map_err(|e| errors::created_problem(&e))
}

/// `given`, else the time now (UTC, whole seconds): when the result is
/// computed. A result is content addressed by its input, the given stamp
/// included, so a cached result keeps the stamp of its computation.
fn stamp_now(given: Option<Created>) -> Created {
    given.unwrap_or_else(|| Created::from_system_time(std::time::SystemTime::now()))
}

fn parse_chart(s: &AppState, chart: &serde_json::Value, figure: Option<FigureType>) -> Result<SizeChart, Problem> {
    parse_chart_with(s.chart_options(), chart, figure)
}

/// A request's size chart (JSON document or CSV text) read with `opts`
/// (`figure`, when given, for ASTM waist columns).
pub(crate) fn parse_chart_with(
    mut opts: SizeChartOptions,
    chart: &serde_json::Value,
    figure: Option<FigureType>,
) -> Result<SizeChart, Problem> {
    if let Some(f) = figure {
        opts.figure = f;
    }
    match chart {
        serde_json::Value::String(csv) => parse_csv(csv, &opts),
        serde_json::Value::Object(_) => parse_json(&chart.to_string(), &opts),
        _ => {
            return Err(
                Problem::bad_request("chart-type", "the chart is a JSON size chart object or CSV text").field("chart")
            )
        }
    }
    .map_err(|e| errors::chart_problem(&e))
}

/// Whether the request's `Content-Type` is `what` (parameters ignored).
fn media_is(headers: &HeaderMap, what: &str) -> bool {
    header_media_is(headers, header::CONTENT_TYPE, what)
}

/// Whether header `name` holds the one media type `what` (parameters
/// ignored; a list of several types is not `what`).
fn header_media_is(headers: &HeaderMap, name: header::HeaderName, what: &str) -> bool {
    headers
        .get(name)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.split(';').next().is_some_and(|m| m.trim().eq_ignore_ascii_case(what)))
}

/// Retailer flow: a size chart and templates to graded results for every size.
///
/// One mannequin per size (the embedded MakeHuman model fitted to the row),
/// every template graded on every size: per-size garment GLB, pattern
/// SVG/DXF/JSON; per template the graded nest (SVG, DXF with grade rules)
/// and grade rules (CSV, .RUL); the fit report. Send JSON, or the CSV chart
/// itself as `text/csv` with the templates in the query. Results are
/// content-addressed and cached.
#[utoipa::path(post, path = "/v1/grade/size-chart", tag = "grading", operation_id = "gradeSizeChart",
    security((), ("apiKey" = [])),
    params(SizeChartQuery),
    request_body(content(
        (SizeChartRequest = "application/json", example = json!({
            "templates": ["straight-skirt"], "base_size": "M",
            "chart": {"unit": "cm", "sizes": [
                {"size": "S", "measurements": {"bust_girth": 86, "waist_girth": 68, "hip_girth": 94}},
                {"size": "M", "measurements": {"bust_girth": 92, "waist_girth": 74, "hip_girth": 100}}]}})),
        (String = "text/csv", example = json!("size,unit,bust_girth,waist_girth_curvy\n8,in,35.5,28.375\n10,in,36.5,29.375\n")),
    )),
    responses(
        (status = 200, description = "The graded result (served from the cache when `cached`).", body = GradeResult),
        api::FlowProblems,
    ))]
async fn grade_size_chart(
    State(s): State<AppState>,
    headers: HeaderMap,
    query: Result<Query<SizeChartQuery>, axum::extract::rejection::QueryRejection>,
    body: axum::body::Body,
) -> Result<Response, Problem> {
    check_key(&s, &headers, false)?;
    let Query(query) = query.map_err(|e| Problem::bad_request("invalid-query", e.body_text()).field("query"))?;
    let bytes = body_bytes(&s, &headers, body).await?;
    let req = if media_is(&headers, "text/csv") {
        let text = std::str::from_utf8(&bytes)
            .map_err(|_| Problem::bad_request("not-utf8", "the CSV is not UTF-8").field("chart"))?;
        let templates = query
            .templates
            .map(|t| t.split(',').map(|x| x.trim().to_owned()).filter(|x| !x.is_empty()).collect())
            .unwrap_or_default();
        SizeChartRequest {
            templates,
            chart: serde_json::Value::String(text.to_owned()),
            base_size: query.base_size,
            figure: query.figure,
            created: query.created,
        }
    } else if media_is(&headers, "application/json") {
        parse_json_body(&bytes)?
    } else {
        return Err(unsupported_media("application/json or text/csv"));
    };
    let field = "templates";
    let templates = resolve_templates(&s, &req.templates, field).await?;
    let chart = parse_chart(&s, &req.chart, req.figure)?;
    let created = parse_created(req.created.as_deref())?;
    // an input that does not serialise is a 500, never hashed as "" (issue #16)
    let canonical = work::json_bytes("size chart", &chart, false)?;
    let stamp = created.map(|c| c.to_rfc3339()).unwrap_or_default();
    let mut parts: Vec<&[u8]> =
        vec![b"size-chart", &canonical, req.base_size.as_deref().unwrap_or("").as_bytes(), stamp.as_bytes()];
    parts.extend(templates.iter().map(|(_, json, _)| json.as_bytes()));
    let id = content_id(&parts);
    let base = req.base_size.clone();
    let ts: Vec<Template> = templates.into_iter().map(|(_, _, t)| t).collect();
    run_flow(&s, id, report::Flow::SizeChart, None, move |ctx| {
        work::size_chart(ctx, &ts, &chart, base.as_deref(), Some(stamp_now(created)), &|_, _, _| {})
    })
    .await
}

fn unsupported_media(what: &str) -> Problem {
    Problem::new(
        StatusCode::UNSUPPORTED_MEDIA_TYPE,
        "unsupported-media-type",
        "Unsupported media type",
        format!("send {what}"),
    )
    .field("Content-Type")
}

/// Web front-end flow: a body scan with landmarks and templates to a graded garment.
///
/// Answers the garment GLB (vertex attribute `_EASE_MM`: distance to the
/// body), the pattern as SVG, DXF and JSON, and the report. Scans are never
/// logged nor stored; their results are forgotten after the scan TTL.
#[utoipa::path(post, path = "/v1/grade/scan", tag = "grading", operation_id = "gradeScan",
    security((), ("apiKey" = [])),
    request_body(content = api::ScanUpload, content_type = "multipart/form-data"),
    responses(
        (status = 200, description = "The graded result (served from the cache when `cached`).", body = GradeResult),
        api::FlowProblems,
    ))]
async fn grade_scan(State(s): State<AppState>, headers: HeaderMap, req: Request) -> Result<Response, Problem> {
    check_key(&s, &headers, false)?;
    if !media_is(&headers, "multipart/form-data") {
        return Err(unsupported_media("multipart/form-data with parts scan, template and optionally landmarks"));
    }
    let (parts, body) = req.into_parts();
    let bytes = body_bytes(&s, &headers, body).await?;
    let req = Request::from_parts(parts, axum::body::Body::from(bytes));
    let ScanParts { scan, landmarks, templates, hints } = read_scan_parts(req, s.0.cfg.max_body_bytes).await?;
    let templates = resolve_templates(&s, &templates, "template").await?;
    // the stated hints and whether landmarks came are part of the input
    let stated = serde_json::to_string(&(&hints, landmarks.is_some())).unwrap_or_default();
    let mut parts: Vec<&[u8]> = vec![b"scan", &scan, landmarks.as_deref().unwrap_or("").as_bytes(), stated.as_bytes()];
    parts.extend(templates.iter().map(|(_, json, _)| json.as_bytes()));
    let id = content_id(&parts);
    let ts: Vec<Template> = templates.into_iter().map(|(_, _, t)| t).collect();
    let ttl = Duration::from_secs(s.0.cfg.scan_ttl_s);
    run_flow(&s, id, report::Flow::Scan, Some(ttl), move |ctx| {
        work::scan(ctx, &ts, &BodyInput { name: "scan", glb: &scan, landmarks: landmarks.as_deref(), hints })
    })
    .await
}

/// The parts of a scan upload.
#[derive(Debug, Clone, PartialEq)]
pub struct ScanParts {
    /// The scan's bytes (GLB or glTF).
    pub scan: Bytes,
    /// The landmarks document, if given.
    pub landmarks: Option<String>,
    /// The template names, in order.
    pub templates: Vec<String>,
    /// The scan's units, up axis and facing, where stated.
    pub hints: FrameHints,
}

/// A stated unit or axis (a text part): its JSON name, e.g. `mm` or `+z`.
fn hint_part<T: serde::de::DeserializeOwned>(name: &str, data: &[u8], allowed: &str) -> Result<T, Problem> {
    let text = std::str::from_utf8(data).unwrap_or("").trim().to_owned();
    serde_json::from_value(serde_json::Value::String(text.clone())).map_err(|_| {
        Problem::bad_request("invalid-part", format!("part `{name}` is `{text}`; allowed: {allowed}")).field(name)
    })
}

/// The next part of a multipart body (its name and bytes) whose body is
/// already within the limit `max`; `None` after the last.
///
/// # Errors
/// [`Problem`]: 413 naming `max` should the reader raise one, else a 400
/// `invalid-multipart` naming the body or the part.
pub(crate) async fn next_part(mp: &mut Multipart, max: usize) -> Result<Option<(String, Bytes)>, Problem> {
    let refusal = |e: axum::extract::multipart::MultipartError, field: &str| {
        if e.status() == StatusCode::PAYLOAD_TOO_LARGE {
            too_large(max)
        } else {
            Problem::bad_request("invalid-multipart", e.body_text()).field(field)
        }
    };
    let Some(field) = mp.next_field().await.map_err(|e| refusal(e, "body"))? else { return Ok(None) };
    let name = field.name().unwrap_or("").to_owned();
    let data = field.bytes().await.map_err(|e| refusal(e, &name))?;
    Ok(Some((name, data)))
}

/// Reads a scan upload (`multipart/form-data` with the parts `scan` and
/// `template`, and optionally `landmarks`, `units`, `up` and `facing`) whose body is already within the limit
/// `max` (named in a 413 should the multipart reader raise one): every
/// refusal a 400 naming the part.
///
/// # Errors
/// [`Problem`]: a malformed multipart body, an unknown or missing part,
/// text that is not UTF-8.
pub async fn read_scan_parts(req: Request, max: usize) -> Result<ScanParts, Problem> {
    let mut mp = Multipart::from_request(req, &())
        .await
        .map_err(|e| Problem::bad_request("invalid-multipart", e.body_text()).field("body"))?;
    let (mut scan, mut landmarks, mut templates) = (None, None, Vec::new());
    let mut hints = FrameHints::default();
    while let Some((name, data)) = next_part(&mut mp, max).await? {
        match name.as_str() {
            "scan" => scan = Some(data),
            "landmarks" => landmarks = Some(data),
            "units" => hints.units = Some(hint_part(&name, &data, "m, cm, mm")?),
            "up" => hints.up = Some(hint_part(&name, &data, "+y, +z")?),
            "facing" => hints.facing = Some(hint_part(&name, &data, "+x, -x, +y, -y, +z, -z")?),
            "template" => {
                let t = std::str::from_utf8(&data)
                    .map_err(|_| Problem::bad_request("not-utf8", "template names are UTF-8").field("template"))?;
                templates.extend(t.split(',').map(|x| x.trim().to_owned()).filter(|x| !x.is_empty()));
            }
            other => {
                return Err(Problem::bad_request("unknown-part", format!("unknown part `{other}`")).field(other));
            }
        }
    }
    let scan =
        scan.ok_or_else(|| Problem::bad_request("missing-part", "the `scan` part (GLB) is missing").field("scan"))?;
    let landmarks = landmarks
        .map(|l| String::from_utf8(l.to_vec()))
        .transpose()
        .map_err(|_| Problem::bad_request("not-utf8", "the landmarks are not UTF-8 JSON").field("landmarks"))?;
    Ok(ScanParts { scan, landmarks, templates, hints })
}

fn stored_result(s: &AppState, id: &str) -> Result<Arc<Stored>, Problem> {
    s.0.results.get(id).ok_or_else(|| Problem::not_found(format!("no result `{id}` (results expire)")))
}

/// A cached grading result.
#[utoipa::path(get, path = "/v1/results/{id}", tag = "grading", operation_id = "getResult",
    security((), ("apiKey" = [])),
    params(("id" = String, Path, description = "The result's content address.")),
    responses(
        (status = 200, description = "The result.", body = GradeResult),
        api::ReadProblems,
    ))]
async fn get_result(
    State(s): State<AppState>,
    headers: HeaderMap,
    Path(id): Path<String>,
) -> Result<Response, Problem> {
    check_key(&s, &headers, false)?;
    let stored = stored_result(&s, &id)?;
    Ok(answer(&stored, true))
}

/// An artefact's bytes as a download: its own media type, or
/// `application/octet-stream` when the request accepts only that
/// (module docs of [`api`]).
fn artefact_response(headers: &HeaderMap, name: &str, media_type: &str, bytes: Vec<u8>) -> Response {
    let disposition = format!("attachment; filename=\"{name}\"");
    let octets = header_media_is(headers, header::ACCEPT, "application/octet-stream");
    let media_type = if octets { "application/octet-stream" } else { media_type };
    let mut resp = bytes.into_response();
    let h = resp.headers_mut();
    if let Ok(v) = HeaderValue::from_str(media_type) {
        h.insert(header::CONTENT_TYPE, v);
    }
    if let Ok(v) = HeaderValue::from_str(&disposition) {
        h.insert(header::CONTENT_DISPOSITION, v);
    }
    resp
}

/// One artefact of a cached result.
#[utoipa::path(get, path = "/v1/results/{id}/{artefact}", tag = "grading", operation_id = "getResultArtefact",
    security((), ("apiKey" = [])),
    params(api::ArtefactPath),
    responses(
        (status = 200, response = api::ArtefactBytes),
        api::ReadProblems,
    ))]
async fn get_result_artefact(
    State(s): State<AppState>,
    headers: HeaderMap,
    Path(api::ArtefactPath { id, artefact: name }): Path<api::ArtefactPath>,
) -> Result<Response, Problem> {
    check_key(&s, &headers, false)?;
    let stored = stored_result(&s, &id)?;
    let a: &Artefact = stored
        .artefacts
        .iter()
        .find(|a| a.name == name)
        .ok_or_else(|| Problem::not_found(format!("result `{id}` has no artefact `{name}`")).field("artefact"))?;
    Ok(artefact_response(&headers, &a.name, a.media_type, a.bytes.clone()))
}

// --- batch jobs ----------------------------------------------------------------------------

fn job_view(s: &AppState, r: &JobRecord) -> JobView {
    let base = format!("/v1/jobs/{}", r.id);
    let progress = s.0.progress.lock().unwrap_or_else(|p| p.into_inner()).get(&r.id).cloned();
    let units = r.units.max(1);
    let (stage, done, total) = match (r.state, progress) {
        (JobState::Done, _) => ("done".to_owned(), units, units),
        (JobState::Failed, _) => ("failed".to_owned(), 0, units),
        (_, Some(p)) => p,
        (JobState::Running, None) => ("running".to_owned(), 0, units),
        (_, None) => ("queued".to_owned(), 0, units),
    };
    JobView {
        id: r.id.clone(),
        artefacts: links(
            &format!("{base}/artefacts"),
            r.artefacts.iter().map(|a| (a.name.clone(), a.media_type.clone(), a.bytes)),
        ),
        href: base,
        state: r.state,
        progress: JobProgress { stage, done, total },
        templates: r.versions.iter().map(|(n, v)| store::Entry { name: n.clone(), version: *v }).collect(),
        error: r.error.clone(),
        report: r.report.clone(),
        timings_ms: r.timings_ms.clone(),
    }
}

/// Manufacturer flow: a batch job (a size chart or bodies, times templates).
///
/// Accepted with 202 once written durably; the job's id is the content
/// address of its inputs (the same request is the same job, and its
/// artefacts are byte-identical run to run). Poll the job URL for
/// progress, then download the artefacts.
#[utoipa::path(post, path = "/v1/jobs", tag = "jobs", operation_id = "submitJob",
    security((), ("apiKey" = [])),
    request_body(content = JobSpec, content_type = "application/json", example = json!({
        "templates": ["straight-skirt", "trousers"], "base_size": "M",
        "size_chart": {"unit": "cm", "sizes": [
            {"size": "S", "measurements": {"bust_girth": 86, "waist_girth": 68, "hip_girth": 94}},
            {"size": "M", "measurements": {"bust_girth": 92, "waist_girth": 74, "hip_girth": 100}}]}})),
    responses(
        (status = 202, description = "Accepted (or the same job, already accepted).", body = JobView,
            headers(("Location" = String, description = "/v1/jobs/{id}"))),
        api::FlowProblems,
    ))]
async fn submit_job(
    State(s): State<AppState>,
    headers: HeaderMap,
    body: axum::body::Body,
) -> Result<Response, Problem> {
    check_key(&s, &headers, false)?;
    if !media_is(&headers, "application/json") {
        return Err(unsupported_media("application/json"));
    }
    let bytes = body_bytes(&s, &headers, body).await?;
    let spec = parse_job_spec(&bytes)?;
    let templates = resolve_templates(&s, &spec.templates, "templates").await?;
    let units = job_units(&spec, s.chart_options(), s.0.cfg.max_job_bodies)?;
    let canonical = work::json_bytes("job", &spec, false)?;
    let mut parts: Vec<&[u8]> = vec![b"job", &canonical];
    parts.extend(templates.iter().map(|(_, json, _)| json.as_bytes()));
    let id = content_id(&parts);
    let location = format!("/v1/jobs/{id}");
    let (me, key) = (s.clone(), id.clone());
    if let Some(existing) = off_executor(move || Ok(me.0.jobs.get(&key)?)).await? {
        if existing.state != JobState::Failed {
            return Ok(
                (StatusCode::ACCEPTED, [(header::LOCATION, location)], Json(job_view(&s, &existing))).into_response()
            );
        }
    }
    // a slot reserved before the record is written: two submissions cannot both take the last one
    let slot = JobSlot::reserve(&s).ok_or_else(|| Problem::busy(30))?;
    let record = JobRecord {
        id: id.clone(),
        spec,
        versions: templates.iter().map(|(v, _, t)| (t.name.clone(), *v)).collect(),
        state: JobState::Queued,
        error: None,
        artefacts: vec![],
        report: None,
        timings_ms: Default::default(),
        units,
    };
    let (me, stored) = (s.clone(), record.clone());
    off_executor(move || Ok(me.0.jobs.put(&stored)?)).await?;
    slot.keep();
    s.0.metrics.jobs.with_label_values(&["queued"]).inc();
    let _ = s.0.job_tx.send(id);
    Ok((StatusCode::ACCEPTED, [(header::LOCATION, location)], Json(job_view(&s, &record))).into_response())
}

/// A job document parsed (JSON, unknown fields refused) with its `created`
/// stamp checked; every refusal a 400 naming the field.
///
/// # Errors
/// [`Problem`].
pub fn parse_job_spec(bytes: &[u8]) -> Result<JobSpec, Problem> {
    let spec: JobSpec = parse_json_body(bytes)?;
    parse_created(spec.created.as_deref())?;
    Ok(spec)
}

/// A parsed job's inputs checked (exactly one of a size chart, read with
/// `chart`, and at most `max_bodies` bodies with unique valid names and
/// base64 scans): its units of progress (sizes or bodies).
///
/// # Errors
/// [`Problem`] naming the field.
pub fn job_units(spec: &JobSpec, chart: SizeChartOptions, max_bodies: usize) -> Result<usize, Problem> {
    Ok(match (&spec.size_chart, spec.bodies.is_empty()) {
        (Some(doc), true) => {
            let chart = parse_chart_with(chart, doc, None)?;
            if let Some(b) = &spec.base_size {
                if !chart.rows.iter().any(|r| &r.size == b) {
                    return Err(Problem::bad_request("unknown-base-size", format!("`{b}` is not a size of the chart"))
                        .field("base_size"));
                }
            }
            chart.rows.len()
        }
        (None, false) => {
            if spec.bodies.len() > max_bodies {
                return Err(Problem::bad_request(
                    "too-many-bodies",
                    format!("{} bodies; at most {} per job", spec.bodies.len(), max_bodies),
                )
                .field("bodies"));
            }
            for (i, b) in spec.bodies.iter().enumerate() {
                valid_name(&b.name).map_err(|p| p.field(format!("bodies[{i}].name")))?;
                if spec.bodies[..i].iter().any(|o| o.name == b.name) {
                    return Err(Problem::bad_request("duplicate-body", format!("body `{}` twice", b.name))
                        .field(format!("bodies[{i}].name")));
                }
                base64::engine::general_purpose::STANDARD.decode(&b.glb_base64).map_err(|e| {
                    Problem::bad_request("invalid-base64", e.to_string()).field(format!("bodies[{i}].glb_base64"))
                })?;
            }
            spec.bodies.len()
        }
        _ => {
            return Err(
                Problem::bad_request("job-input", "give exactly one of `size_chart` and `bodies`").field("size_chart")
            )
        }
    })
}

/// A reserved place among [`ServiceConfig::max_pending_jobs`]: given back
/// when dropped unless kept (the job's end gives it back then).
struct JobSlot<'a>(Option<&'a AppState>);

impl<'a> JobSlot<'a> {
    fn reserve(s: &'a AppState) -> Option<Self> {
        use std::sync::atomic::Ordering;
        if s.0.pending_jobs.fetch_add(1, Ordering::AcqRel) >= s.0.cfg.max_pending_jobs {
            s.0.pending_jobs.fetch_sub(1, Ordering::AcqRel);
            return None;
        }
        Some(Self(Some(s)))
    }

    fn keep(mut self) {
        self.0 = None;
    }
}

impl Drop for JobSlot<'_> {
    fn drop(&mut self) {
        if let Some(s) = self.0 {
            s.0.pending_jobs.fetch_sub(1, std::sync::atomic::Ordering::AcqRel);
        }
    }
}

/// Runs one job to its end on the calling (blocking) thread.
fn run_job(s: &AppState, id: &str) {
    let Ok(Some(mut r)) = s.0.jobs.get(id) else { return };
    if !matches!(r.state, JobState::Queued | JobState::Running) {
        return;
    }
    let m = &s.0.metrics;
    m.jobs.with_label_values(&[r.state.as_str()]).dec();
    m.jobs.with_label_values(&["running"]).inc();
    // what a poll reads from now on (issue #16: the record said `queued` until the end)
    r.state = JobState::Running;
    if let Err(e) = s.0.jobs.put(&r) {
        tracing::error!(error = %e, "job state could not be stored");
    }
    // wait for the renderer's start-up to end
    while s.0.renderer.get().is_none() {
        std::thread::sleep(Duration::from_millis(50));
    }
    // a panic ends the job as failed (its place given back), not as `running` for ever
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run_job_work(s, &r))).unwrap_or_else(|_| {
        tracing::error!("job panicked");
        Err(Problem::internal())
    });
    m.jobs.with_label_values(&["running"]).dec();
    let mut stored = Vec::new();
    match result {
        Ok(outcome) => {
            r.state = JobState::Done;
            m.observe_stages(&outcome.timings);
            r.timings_ms = outcome.timings;
            r.report = Some(outcome.report);
            for a in outcome.artefacts {
                r.artefacts.push(ArtefactEntry {
                    name: a.name.clone(),
                    media_type: a.media_type.into(),
                    bytes: a.bytes.len(),
                });
                stored.push((a.name, a.bytes));
            }
        }
        Err(p) => {
            r.state = JobState::Failed;
            r.error = Some(p);
        }
    }
    m.jobs.with_label_values(&[r.state.as_str()]).inc();
    // scans are not kept past the job
    for b in &mut r.spec.bodies {
        b.glb_base64.clear();
    }
    if let Err(e) = s.0.jobs.finish(&r, &stored) {
        tracing::error!(error = %e, "job result could not be stored");
    }
    s.0.progress.lock().unwrap_or_else(|p| p.into_inner()).remove(id);
    s.0.pending_jobs.fetch_sub(1, std::sync::atomic::Ordering::AcqRel);
}

fn run_job_work(s: &AppState, r: &JobRecord) -> Result<Outcome, Problem> {
    let mut templates = Vec::new();
    for (name, v) in &r.versions {
        let t = s.0.store.get(name, Some(*v))?.1;
        templates.push(t);
    }
    let ctx = s.work_context()?;
    let id = r.id.clone();
    let progress = move |stage: &str, done: usize, total: usize| {
        s.0.progress.lock().unwrap_or_else(|p| p.into_inner()).insert(id.clone(), (stage.to_owned(), done, total));
    };
    let created = stamp_now(parse_created(r.spec.created.as_deref())?);
    let outcome = if let Some(chart) = &r.spec.size_chart {
        let chart = parse_chart(s, chart, None)?;
        work::size_chart(&ctx, &templates, &chart, r.spec.base_size.as_deref(), Some(created), &progress)?
    } else {
        let mut decoded = Vec::new();
        for b in &r.spec.bodies {
            let glb = base64::engine::general_purpose::STANDARD
                .decode(&b.glb_base64)
                .map_err(|e| Problem::bad_request("invalid-base64", e.to_string()))?;
            let hints = FrameHints { units: b.units, up: b.up, facing: b.facing };
            decoded.push((b.name.clone(), glb, b.landmarks.as_ref().map(ToString::to_string), hints));
        }
        let inputs: Vec<BodyInput<'_>> = decoded
            .iter()
            .map(|(n, g, l, h)| BodyInput { name: n, glb: g, landmarks: l.as_deref(), hints: *h })
            .collect();
        work::bodies(&ctx, &templates, &inputs, r.spec.base_size.as_deref(), Some(created), &progress)?
    };
    Ok(outcome)
}

/// The job `id`, read off the executor.
async fn job(s: &AppState, id: &str) -> Result<JobRecord, Problem> {
    let (me, key) = (s.clone(), id.to_owned());
    off_executor(move || Ok(me.0.jobs.get(&key)?)).await?.ok_or_else(|| Problem::not_found(format!("no job `{id}`")))
}

/// A job's state, progress, report and artefacts.
#[utoipa::path(get, path = "/v1/jobs/{id}", tag = "jobs", operation_id = "getJob",
    security((), ("apiKey" = [])),
    params(("id" = String, Path, description = "The job's content address.")),
    responses(
        (status = 200, description = "The job.", body = JobView),
        api::ReadProblems,
    ))]
async fn get_job(State(s): State<AppState>, headers: HeaderMap, Path(id): Path<String>) -> Result<Response, Problem> {
    check_key(&s, &headers, false)?;
    let r = job(&s, &id).await?;
    Ok(Json(job_view(&s, &r)).into_response())
}

/// One artefact of a finished job.
#[utoipa::path(get, path = "/v1/jobs/{id}/artefacts/{artefact}", tag = "jobs", operation_id = "getJobArtefact",
    security((), ("apiKey" = [])),
    params(api::ArtefactPath),
    responses(
        (status = 200, response = api::ArtefactBytes),
        api::ReadProblems,
    ))]
async fn get_job_artefact(
    State(s): State<AppState>,
    headers: HeaderMap,
    Path(api::ArtefactPath { id, artefact: name }): Path<api::ArtefactPath>,
) -> Result<Response, Problem> {
    check_key(&s, &headers, false)?;
    let r = job(&s, &id).await?;
    let entry = r
        .artefacts
        .iter()
        .find(|a| a.name == name)
        .ok_or_else(|| Problem::not_found(format!("job `{id}` has no artefact `{name}`")).field("artefact"))?;
    let (me, key, file) = (s.clone(), id.clone(), entry.name.clone());
    let bytes = off_executor(move || Ok(me.0.jobs.artefact(&key, &file)?))
        .await?
        .ok_or_else(|| Problem::not_found("artefact missing"))?;
    Ok(artefact_response(&headers, &entry.name, &entry.media_type, bytes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use axum::body::Body;
    use axum::http::Request;
    use http_body_util::BodyExt;
    use tower::ServiceExt;

    pub(crate) fn state() -> (AppState, PathBuf) {
        static N: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "grade3d-svc-{}-{}",
            std::process::id(),
            N.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
        ));
        let _ = std::fs::remove_dir_all(&dir);
        let mut cfg = ServiceConfig::with_data_dir(dir.clone());
        cfg.api_key = Some("k".into());
        (AppState::open(cfg).unwrap(), dir)
    }

    #[tokio::test]
    async fn healthz_answers_ok_and_unknown_routes_are_problems() {
        let (s, dir) = state();
        let resp = app(s.clone()).oneshot(Request::get("/healthz").body(Body::empty()).unwrap()).await.unwrap();
        assert_eq!(resp.status(), StatusCode::OK);
        let resp = app(s.clone()).oneshot(Request::get("/nope").body(Body::empty()).unwrap()).await.unwrap();
        assert_eq!(resp.status(), StatusCode::NOT_FOUND);
        assert_eq!(resp.headers()[header::CONTENT_TYPE], problem::PROBLEM_JSON);
        let resp = app(s.clone()).oneshot(Request::patch("/v1/templates").body(Body::empty()).unwrap()).await.unwrap();
        assert_eq!(resp.status(), StatusCode::METHOD_NOT_ALLOWED);
        assert_eq!(resp.headers()[header::CONTENT_TYPE], problem::PROBLEM_JSON);
        // not ready before the GPU start-up ends
        let resp = app(s).oneshot(Request::get("/readyz").body(Body::empty()).unwrap()).await.unwrap();
        assert_eq!(resp.status(), StatusCode::SERVICE_UNAVAILABLE);
        let _ = std::fs::remove_dir_all(dir);
    }

    /// Router coverage (issue #16): every operation of the generated
    /// document reaches a handler of [`app`] (neither the unknown-route
    /// fallback nor 405), and [`app`] registers no route outside
    /// [`routes`], the list the document is made from.
    #[tokio::test]
    async fn every_documented_operation_is_routed_and_every_route_documented() {
        let (s, dir) = state();
        let doc = api::openapi();
        let mut operations = 0;
        for (path, item) in &doc.paths.paths {
            let methods = [
                ("GET", item.get.is_some()),
                ("POST", item.post.is_some()),
                ("PUT", item.put.is_some()),
                ("DELETE", item.delete.is_some()),
                ("PATCH", item.patch.is_some()),
            ];
            for (method, _) in methods.iter().filter(|m| m.1) {
                operations += 1;
                let uri = path
                    .replace("{name}", "no-such-template")
                    .replace("{id}", "0")
                    .replace("{artefact}", "report.json");
                let req = Request::builder().method(*method).uri(&uri).body(Body::empty()).unwrap();
                let resp = app(s.clone()).oneshot(req).await.unwrap();
                assert_ne!(resp.status(), StatusCode::METHOD_NOT_ALLOWED, "{method} {path}");
                let body = resp.into_body().collect().await.unwrap().to_bytes();
                let text = String::from_utf8_lossy(&body);
                assert!(!text.contains("no such route"), "{method} {path} is documented but not routed: {text}");
            }
        }
        assert_eq!(operations, 19, "the service's 19 operations");
        // the reverse: no route bypasses the documented list
        let code = include_str!("lib.rs");
        let code = &code[..code.find("#[cfg(test)]").unwrap_or(code.len())];
        for bypass in [".route(", ".route_service(", ".nest(", ".nest_service(", ".merge("] {
            assert!(!code.contains(bypass), "app() registers a route with `{bypass}` outside routes()");
        }
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn a_running_job_reads_running_and_a_finished_one_keeps_its_total() {
        // regression (issue #16): the record read `queued` while the job ran, and a finished
        // job's progress read 1 of 1 after 12 of 12
        let (s, dir) = state();
        let spec = JobSpec { templates: vec![], size_chart: None, bodies: vec![], base_size: None, created: None };
        let mut r = JobRecord {
            id: "j".into(),
            spec,
            versions: vec![],
            state: JobState::Running,
            error: None,
            artefacts: vec![],
            report: None,
            timings_ms: Default::default(),
            units: 12,
        };
        let v = job_view(&s, &r);
        assert_eq!((v.state, v.progress.total), (JobState::Running, 12), "{v:?}");
        r.state = JobState::Done;
        let v = job_view(&s, &r);
        assert_eq!((v.progress.done, v.progress.total), (12, 12), "{v:?}");
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn job_slots_are_bounded_reserved_at_once_and_given_back() {
        // regression (issue #16): admission read the Prometheus gauges, after the check and
        // before the record, so two submissions could both take the last place
        let dir = std::env::temp_dir().join(format!("grade3d-svc-slots-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let mut cfg = ServiceConfig::with_data_dir(dir.clone());
        cfg.max_pending_jobs = 2;
        let s = AppState::open(cfg).unwrap();
        let a = JobSlot::reserve(&s).expect("first");
        let b = JobSlot::reserve(&s).expect("second");
        assert!(JobSlot::reserve(&s).is_none(), "a third place");
        drop(b);
        JobSlot::reserve(&s).expect("given back when dropped").keep();
        a.keep();
        assert!(JobSlot::reserve(&s).is_none(), "kept places stay taken");
        assert_eq!(s.0.pending_jobs.load(std::sync::atomic::Ordering::Acquire), 2);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[tokio::test(flavor = "current_thread")]
    async fn store_calls_run_off_the_executor_thread() {
        // regression (issue #16): redb reads and fsync'd writes ran on the async executor
        let executor = std::thread::current().id();
        let on = off_executor(|| Ok(std::thread::current().id())).await.unwrap();
        assert_ne!(on, executor);
        let (s, dir) = state();
        let resp = app(s).oneshot(Request::get("/v1/templates").body(Body::empty()).unwrap()).await.unwrap();
        assert_eq!(resp.status(), StatusCode::OK);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn api_keys_match_only_when_equal() {
        assert!(keys_match("k3y", "k3y"));
        for wrong in ["", "k3", "k3y ", "K3Y", "k3z", "a much longer key than the real one"] {
            assert!(!keys_match(wrong, "k3y"), "{wrong:?}");
        }
    }

    #[test]
    fn the_default_address_is_loopback_8080() {
        // the README's first command serves here (its end-to-end test runs on a free port)
        let c = ServiceConfig::with_data_dir(PathBuf::from("d"));
        assert_eq!(c.addr, "127.0.0.1:8080".parse().unwrap());
        assert_eq!(c.request_timeout(), Duration::from_secs(120));
        assert!(positive_seconds("0").is_err() && positive_seconds("nan").is_err() && positive_seconds("-1").is_err());
        assert_eq!(positive_seconds("0.001"), Ok(0.001));
    }

    #[tokio::test]
    async fn writes_need_the_key() {
        let (s, dir) = state();
        let delete = |key: Option<&str>| {
            let mut req = Request::delete("/v1/templates/trousers");
            if let Some(k) = key {
                req = req.header(header::AUTHORIZATION, format!("Bearer {k}"));
            }
            app(s.clone()).oneshot(req.body(Body::empty()).unwrap())
        };
        assert_eq!(delete(None).await.unwrap().status(), StatusCode::UNAUTHORIZED);
        assert_eq!(delete(Some("wrong")).await.unwrap().status(), StatusCode::UNAUTHORIZED);
        assert_eq!(delete(Some("k")).await.unwrap().status(), StatusCode::NO_CONTENT);
        assert_eq!(s.0.store.list().unwrap().len(), crate::template::library::builtin().unwrap().len() - 1);
        let _ = std::fs::remove_dir_all(dir);
    }
}
