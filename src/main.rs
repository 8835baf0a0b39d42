//! `grade3d` command line: the service and the data tools.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "grade3d", version, about = "Automated 3D garment grading")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the HTTP service.
    Serve(grade3d::service::ServiceConfig),
    /// Fit one mannequin per size of a size chart (CSV or JSON) and print the residuals.
    FitChart {
        /// The size chart.
        chart: PathBuf,
        /// ASTM figure type for the waist column (curvy or straight).
        #[arg(long, default_value = "curvy")]
        figure: String,
        /// The run's base size: fitted, the others graded from its body
        /// (default: the middle row, as the service's chart flow).
        #[arg(long)]
        base_size: Option<String>,
        /// Fit every size on its own instead of grading the base size's body.
        #[arg(long)]
        independent: bool,
    },
    /// Grade a size chart or body scans offline and write exactly the artefacts the
    /// service returns for the same input (patterns, nests, grade rules, meshes, report).
    /// Exit code 2: bad input (the message names the file); 1: the grade failed.
    Grade(GradeArgs),
    /// Derive the feature human model of a body scan and print its measurements and frames.
    Measure {
        /// The body (GLB or glTF with embedded buffers).
        body: PathBuf,
        /// Its landmarks JSON.
        landmarks: PathBuf,
    },
    /// Flatten one panel (OBJ) with LSCM + ARAP and print the result as JSON
    /// (what `benches/peer_flatten.py` compares with libigl).
    Flatten {
        /// The panel, a triangulated disc (OBJ).
        panel: PathBuf,
        /// Print JSON (the only output format; kept for the peer script's command line).
        #[arg(long)]
        json: bool,
        /// Plain ARAP from the LSCM start: no boundary springs, no boundary truing
        /// (to compare like with like with other ARAP implementations).
        #[arg(long)]
        plain: bool,
    },
    /// Author a template from a designed garment (issue #18): GLB with one mesh per pattern
    /// piece or OBJ with one group per piece, draped on its design body. Writes the template
    /// JSON (ready for `POST /v1/templates`) and prints what was made and what could not be
    /// mapped, as `POST /v1/templates/from-garment` answers. Exit code 2: bad input; 1: failed.
    Author {
        /// The garment file.
        garment: PathBuf,
        /// The template's name.
        #[arg(long)]
        name: String,
        /// Its design body: `reference` or `makehuman-base`. (An avatar the garment was draped
        /// on is kept with the template by the service: `POST /v1/templates/from-garment` with
        /// `body_scan`.)
        #[arg(long, default_value = "reference", conflicts_with = "body_chart")]
        body: String,
        /// Or a size chart (CSV or JSON) one of whose sizes is the design body...
        #[arg(long, requires = "body_size")]
        body_chart: Option<PathBuf>,
        /// ...this size (its label): the mannequin fitted to it.
        #[arg(long, requires = "body_chart")]
        body_size: Option<String>,
        /// The garment's units: `m`, `cm` or `mm` (default: found from its size).
        #[arg(long)]
        units: Option<String>,
        /// Authoring options, a JSON file (the request's `options` part).
        #[arg(long)]
        options: Option<PathBuf>,
        /// Where to write the template JSON.
        #[arg(long)]
        out: PathBuf,
    },
    /// Print the service's OpenAPI document (YAML), generated from its router and types:
    /// what `openapi.yaml` holds (`grade3d openapi > openapi.yaml`).
    Openapi,
    /// Grade every built-in template on the reference body and write each panel as OBJ
    /// (the inputs of `benches/peer_flatten.py`).
    Panels {
        /// Output folder.
        #[arg(long, default_value = "target/panels")]
        dir: PathBuf,
    },
}

/// `grade3d grade`: a size chart (`--chart`) or scans (`--scan`, optionally with `--landmarks`).
#[derive(clap::Args)]
struct GradeArgs {
    /// The size chart, CSV or JSON (the service's `POST /v1/grade/size-chart` flow).
    #[arg(long, conflicts_with = "scan", required_unless_present = "scan")]
    chart: Option<PathBuf>,
    /// A body scan, GLB (repeat for several bodies: a run whose nests span them).
    #[arg(long)]
    scan: Vec<PathBuf>,
    /// The landmarks JSON of each `--scan`, in the same order; none at all:
    /// every landmark is read off the body model registered to each scan.
    #[arg(long)]
    landmarks: Vec<PathBuf>,
    /// The scans' units: m, cm or mm. Default: found from each scan's height.
    #[arg(long, value_parser = ["m", "cm", "mm"])]
    units: Option<String>,
    /// The scans' up axis: +y or +z. Default: the longer of the two extents.
    #[arg(long, value_parser = ["+y", "+z"], allow_hyphen_values = true)]
    up: Option<String>,
    /// The direction the bodies face, in the scans' axes: +x, -x, +y, -y, +z or -z.
    /// Default: where the feet point.
    #[arg(long, value_parser = ["+x", "-x", "+y", "-y", "+z", "-z"], allow_hyphen_values = true)]
    facing: Option<String>,
    /// Templates: built-in names or template JSON files, comma-separated.
    #[arg(long, value_delimiter = ',', required = true)]
    templates: Vec<String>,
    /// The base size of the grade rules (a chart's size, or a scan's file stem).
    /// Default: the chart's middle row, or the first scan.
    #[arg(long)]
    base_size: Option<String>,
    /// ASTM figure type of a women's chart without it (curvy or straight).
    #[arg(long)]
    figure: Option<String>,
    /// Output folder (created; existing files of the same names are replaced).
    #[arg(long)]
    out: PathBuf,
    /// Creation date and time written into the `.RUL` files, RFC 3339
    /// (`2026-12-03T14:05:00Z`). Default: `SOURCE_DATE_EPOCH` (seconds since
    /// 1970, the reproducible-builds convention) where set, else now. The
    /// service's `created` gives the same bytes for the same stamp.
    #[arg(long)]
    created: Option<String>,
    /// Also print the wall time per stage, summed over the grades, as one
    /// JSON object on stderr (`timings_ms {...}`), as the service reports
    /// them in `timings_ms`; benches/chart.sh reads it.
    #[arg(long)]
    timings: bool,
    /// What draws the body's depth maps: `auto` (wgpu on a GPU, the CPU
    /// rasteriser where wgpu's adapter is a CPU driver or there is none),
    /// `wgpu` or `cpu`.
    #[arg(long, env = "GRADE3D_RENDERER", default_value_t = grade3d::collide::render::RendererChoice::Auto)]
    renderer: grade3d::collide::render::RendererChoice,
}

/// Bad input to a command: exit code 2.
#[derive(Debug)]
struct BadInput(String);

impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for BadInput {}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()))
        .with_writer(std::io::stderr)
        // colours for a terminal only: a log file or collector gets plain text (issue #16)
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            if e.downcast_ref::<BadInput>().is_some() {
                ExitCode::from(2)
            } else {
                ExitCode::FAILURE
            }
        }
    }
}

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.command {
        Command::Serve(cfg) => serve(cfg)?,
        Command::FitChart { chart, figure, base_size, independent } => {
            fit_chart(&chart, &figure, base_size.as_deref(), independent)?
        }
        Command::Grade(args) => grade_offline(&args)?,
        Command::Flatten { panel, json: _, plain } => flatten_panel(&panel, plain)?,
        Command::Panels { dir } => write_panels(&dir)?,
        Command::Openapi => print!("{}", grade3d::service::api::openapi_yaml()?),
        Command::Measure { body, landmarks } => measure_body(&body, &landmarks)?,
        Command::Author { garment, name, body, body_chart, body_size, units, options, out } => {
            let chart = body_chart.as_deref().zip(body_size.as_deref());
            author_template(&garment, name, &body, chart, units.as_deref(), options.as_deref(), &out)?
        }
    }
    Ok(())
}

/// `grade3d author`: the service's authoring ([`grade3d::service::author`])
/// on files.
fn author_template(
    garment: &std::path::Path,
    name: String,
    body: &str,
    chart: Option<(&std::path::Path, &str)>,
    units: Option<&str>,
    options: Option<&std::path::Path>,
    out: &std::path::Path,
) -> Result<(), Box<dyn std::error::Error>> {
    use grade3d::service::author::{author_on, chart_size, AuthorParts, PartsBody};
    use grade3d::template::from_garment::{design_body, DesignBody};
    let bad = |what: String| -> Box<dyn std::error::Error> { Box::new(BadInput(what)) };
    let bytes = std::fs::read(garment).map_err(|e| bad(format!("{}: {e}", garment.display())))?;
    // an enum's value by its JSON name
    let word = |text: &str| serde_json::Value::String(text.to_owned());
    let which: DesignBody = match chart {
        Some((path, size)) => {
            let text = std::fs::read_to_string(path).map_err(|e| bad(format!("{}: {e}", path.display())))?;
            chart_size(&word(&text), size, &Default::default(), ("--body-chart", "--body-size"))
                .map_err(|p| bad(format!("{}: {}", p.field.unwrap_or_default(), p.detail)))?
        }
        None => serde_json::from_value(word(body))
            .map_err(|_| bad(format!("--body `{body}`: allowed reference, makehuman-base")))?,
    };
    let units = match units {
        Some(u) => Some(serde_json::from_value(word(u)).map_err(|_| bad(format!("--units `{u}`: allowed m, cm, mm")))?),
        None => None,
    };
    let options = match options {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| bad(format!("{}: {e}", path.display())))?;
            serde_json::from_str(&text).map_err(|e| bad(format!("{}: {e}", path.display())))?
        }
        None => Default::default(),
    };
    // a chart size that cannot be fitted is the input's fault; the embedded model's failure is not
    let built = design_body(&which).map_err(|e| match e {
        grade3d::template::library::AuthorError::Fit(f) => bad(format!("--body-chart: {f}")),
        e => Box::new(e) as Box<dyn std::error::Error>,
    })?;
    let parts = AuthorParts { garment: bytes.into(), name, body: PartsBody::Design(which.clone()), units, options };
    let (template, report) =
        author_on(&parts, &built, which, None).map_err(|e| bad(format!("{}: {e}", garment.display())))?;
    std::fs::write(out, template.to_json()).map_err(|e| format!("{}: {e}", out.display()))?;
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}

/// The `.RUL` creation stamp of `grade3d grade`: `--created`, else
/// `SOURCE_DATE_EPOCH`, else the time now; a message naming the bad one.
fn creation_stamp(given: Option<&str>) -> Result<grade3d::pattern::export::rul::Created, String> {
    use grade3d::pattern::export::rul::Created;
    if let Some(text) = given {
        return Created::from_rfc3339(text).map_err(|e| format!("--created: {e}"));
    }
    if let Ok(epoch) = std::env::var("SOURCE_DATE_EPOCH") {
        let secs: i64 = epoch
            .trim()
            .parse()
            .map_err(|_| format!("SOURCE_DATE_EPOCH: `{epoch}` is not whole seconds since 1970"))?;
        return Created::from_unix(secs).map_err(|e| format!("SOURCE_DATE_EPOCH: {e}"));
    }
    Ok(Created::from_system_time(std::time::SystemTime::now()))
}

/// `grade3d grade` (see [`GradeArgs`]): the service's flows
/// (`grade3d::service::work`) run here, their artefacts written to `--out`.
fn grade_offline(args: &GradeArgs) -> Result<(), Box<dyn std::error::Error>> {
    use grade3d::collide::cache::{ObstacleCache, ObstacleCacheOptions};
    use grade3d::collide::render::Renderer;
    use grade3d::mannequin::size_chart;
    use grade3d::service::problem::Problem;
    use grade3d::service::work::{self, BodyInput, WorkContext, WorkOptions};
    use grade3d::template::format::Template;

    // the embedded body model decodes (about 45 ms, once per process) while the templates are read
    // and the renderer starts; the flow's first use waits for it (and reports its error, if any)
    std::thread::spawn(|| grade3d::mannequin::model::BodyModel::embedded().map(|_| ()));
    let bad = |m: String| -> Box<dyn std::error::Error> { Box::new(BadInput(m)) };
    let read = |p: &std::path::Path| std::fs::read(p).map_err(|e| bad(format!("{}: {e}", p.display())));
    let text = |p: &std::path::Path| -> Result<String, Box<dyn std::error::Error>> {
        String::from_utf8(read(p)?).map_err(|_| bad(format!("{}: not UTF-8 text", p.display())))
    };
    // templates: built-in names, or template JSON files
    let library = grade3d::template::library::builtin().map_err(|(n, e)| format!("built-in template {n}: {e}"))?;
    let mut templates: Vec<Template> = Vec::with_capacity(args.templates.len());
    for name in &args.templates {
        let t = match library.iter().find(|t| &t.name == name) {
            Some(t) => t.clone(),
            None if std::path::Path::new(name).is_file() => {
                Template::from_json(&text(std::path::Path::new(name))?).map_err(|e| bad(format!("{name}: {e}")))?
            }
            None => {
                let known: Vec<&str> = library.iter().map(|t| t.name.as_str()).collect();
                return Err(bad(format!("--templates: no built-in template or file `{name}` (built-in: {known:?})")));
            }
        };
        templates.push(t);
    }
    let renderer = match Renderer::new(args.renderer) {
        Ok(r) => {
            tracing::info!(renderer = %r.describe(), "depth-map renderer ready");
            Some(std::sync::Arc::new(r))
        }
        Err(e) => {
            tracing::warn!(error = %e, "no wgpu adapter: grading without collision avoidance");
            None
        }
    };
    let ctx = WorkContext {
        renderer,
        obstacles: std::sync::Arc::new(ObstacleCache::new(ObstacleCacheOptions::default())),
        blocks: Default::default(),
        design_bodies: grade3d::service::work::DesignBodyResolver::core(),
        opts: WorkOptions::default(),
    };
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg:>8} [{bar:30}] {pos}/{len} {elapsed}")
            .map_err(|e| e.to_string())?
            .progress_chars("=> "),
    );
    let progress = |stage: &str, done: usize, total: usize| {
        bar.set_length(total as u64);
        bar.set_position(done as u64);
        bar.set_message(stage.to_owned());
    };
    // bad input is the caller's (exit 2), anything else a failure (exit 1)
    let fail = |e: work::WorkError, file: &std::path::Path| -> Box<dyn std::error::Error> {
        let m = format!("{}: {e}", file.display());
        let status = Problem::from(e).status;
        if (400..500).contains(&status) {
            bad(m)
        } else {
            m.into()
        }
    };
    let created = Some(creation_stamp(args.created.as_deref()).map_err(bad)?);
    let outcome = if let Some(chart_path) = &args.chart {
        let mut opts = size_chart::SizeChartOptions::default();
        match args.figure.as_deref() {
            None => {}
            Some("curvy") => opts.figure = size_chart::FigureType::Curvy,
            Some("straight") => opts.figure = size_chart::FigureType::Straight,
            Some(other) => return Err(bad(format!("--figure: `{other}` is not curvy or straight"))),
        }
        let t = text(chart_path)?;
        let chart = size_chart::parse_text(&t, &opts).map_err(|e| bad(format!("{}: {e}", chart_path.display())))?;
        work::size_chart(&ctx, &templates, &chart, args.base_size.as_deref(), created, &progress)
            .map_err(|e| fail(e, chart_path))?
    } else {
        if !args.landmarks.is_empty() && args.landmarks.len() != args.scan.len() {
            return Err(bad(format!(
                "{} --scan but {} --landmarks: give one landmarks file per scan, or none",
                args.scan.len(),
                args.landmarks.len()
            )));
        }
        // the values are the options' own (clap checked them), named as the API names them
        use grade3d::body::frame::{Axis, FrameHints, Units};
        let axis = |v: &str| match v {
            "+x" => Some(Axis::PosX),
            "-x" => Some(Axis::NegX),
            "+y" => Some(Axis::PosY),
            "-y" => Some(Axis::NegY),
            "+z" => Some(Axis::PosZ),
            "-z" => Some(Axis::NegZ),
            _ => None,
        };
        let units = |v: &str| match v {
            "m" => Some(Units::Metres),
            "cm" => Some(Units::Centimetres),
            "mm" => Some(Units::Millimetres),
            _ => None,
        };
        let hints = FrameHints {
            units: args.units.as_deref().and_then(units),
            up: args.up.as_deref().and_then(axis),
            facing: args.facing.as_deref().and_then(axis),
        };
        let mut bodies = Vec::with_capacity(args.scan.len());
        for (i, scan) in args.scan.iter().enumerate() {
            let lm = args.landmarks.get(i).map(|l| text(l)).transpose()?;
            // one scan is named as the service names it; several by their file stems
            let name = if args.scan.len() == 1 {
                "scan".to_owned()
            } else {
                scan.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()
            };
            bodies.push((name, read(scan)?, lm, scan.clone()));
        }
        let inputs: Vec<BodyInput<'_>> =
            bodies.iter().map(|(n, g, l, _)| BodyInput { name: n, glb: g, landmarks: l.as_deref(), hints }).collect();
        let first = args.scan.first().cloned().unwrap_or_default();
        work::bodies(&ctx, &templates, &inputs, args.base_size.as_deref(), created, &progress)
            .map_err(|e| fail(e, &first))?
    };
    bar.finish_and_clear();
    std::fs::create_dir_all(&args.out).map_err(|e| bad(format!("{}: {e}", args.out.display())))?;
    for a in &outcome.artefacts {
        let path = args.out.join(&a.name);
        std::fs::write(&path, &a.bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    }
    println!("wrote {} artefacts to {}", outcome.artefacts.len(), args.out.display());
    if args.timings {
        eprintln!("timings_ms {}", serde_json::to_string(&outcome.timings)?);
    }
    Ok(())
}

fn fit_chart(
    path: &std::path::Path,
    figure: &str,
    base: Option<&str>,
    independent: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    use grade3d::mannequin::{fit, model::BodyModel, size_chart};
    let figure = match figure {
        "curvy" => size_chart::FigureType::Curvy,
        "straight" => size_chart::FigureType::Straight,
        other => return Err(format!("unknown figure type `{other}` (curvy or straight)").into()),
    };
    let text = std::fs::read_to_string(path)?;
    let opts = size_chart::SizeChartOptions { figure, ..Default::default() };
    let chart = size_chart::parse_text(&text, &opts)?;
    let model = BodyModel::embedded()?;
    let mut out = std::io::stdout().lock();
    let fit_opts = fit::FitOptions { independent_sizes: independent, ..fit::FitOptions::for_sex(chart.sex) };
    let base_row = match base {
        Some(b) => chart.rows.iter().position(|r| r.size == b).ok_or_else(|| format!("no size `{b}` in the chart"))?,
        None => chart.rows.len() / 2,
    };
    let fits = fit::fit_chart(model, &chart.rows, base_row, &fit_opts)?;
    for (row, f) in chart.rows.iter().zip(&fits) {
        write!(out, "size {:>4}:", row.size)?;
        for (id, r) in &f.residuals {
            write!(out, "  {id} {:.1} cm ({:+.2} mm)", r.target_m * 100.0, r.error_mm())?;
        }
        writeln!(out)?;
    }
    Ok(())
}

fn measure_body(body: &std::path::Path, landmarks: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    let mesh = grade3d::io::gltf::read_mesh(&std::fs::read(body)?, &Default::default())?;
    let lm = grade3d::io::landmarks::parse_landmarks(&std::fs::read_to_string(landmarks)?)?;
    let fb = grade3d::body::derive::derive_features(mesh, &lm, &Default::default())?;
    let mut out = std::io::stdout().lock();
    for (id, v) in grade3d::body::measure::measure(&fb, &Default::default()) {
        writeln!(out, "{id:>18}  {:7.1} cm", v * 100.0)?;
    }
    for (id, p) in &fb.points {
        writeln!(
            out,
            "{id:>18}  {:+.4} {:+.4} {:+.4}  |t1.(t2xn)| {:.3}",
            p.position.x,
            p.position.y,
            p.position.z,
            p.frame.triple().abs()
        )?;
    }
    Ok(())
}

fn flatten_panel(path: &std::path::Path, plain: bool) -> Result<(), Box<dyn std::error::Error>> {
    use grade3d::pattern::flatten::{distortion, flatten, lscm, FlattenOptions};
    use grade3d::pattern::panels::{PanelFace, PanelVertex};
    use typed_index_collections::TiVec;
    let (positions, triangles) = grade3d::io::obj::read_obj(&std::fs::read_to_string(path)?)?;
    // the OBJ's numbering is the panel's
    let positions: TiVec<PanelVertex, _> = positions.into();
    let triangles: TiVec<PanelFace, _> = triangles.iter().map(|t| t.map(PanelVertex)).collect();
    let start = std::time::Instant::now();
    lscm(&positions, &triangles)?;
    let lscm_ms = start.elapsed().as_secs_f64() * 1e3;
    let start = std::time::Instant::now();
    let opts = if plain {
        FlattenOptions { boundary_weight: 0.0, exact_boundary: false, ..Default::default() }
    } else {
        FlattenOptions::default()
    };
    let flat = flatten(&positions, &triangles, &opts)?;
    let total_ms = start.elapsed().as_secs_f64() * 1e3;
    let d = distortion(&positions, &triangles, &flat.uv);
    let out = serde_json::json!({
        "vertices": positions.len(),
        "triangles": triangles.len(),
        "lscm_ms": lscm_ms,
        "arap_ms": (total_ms - lscm_ms).max(0.0),
        "total_ms": total_ms,
        "iterations": flat.iterations,
        "converged": flat.converged,
        "distortion": d,
        "uv": flat.uv.iter().map(|p| [p.x, p.y]).collect::<Vec<_>>(),
    });
    println!("{out}");
    Ok(())
}

fn write_panels(dir: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    use grade3d::collide::cache::Obstacle;
    use grade3d::collide::render::{RenderOptions, Renderer, RendererChoice};
    use grade3d::geom::winding::WindingOptions;
    std::fs::create_dir_all(dir)?;
    let body = grade3d::template::library::reference_body()?;
    let renderer = Renderer::new(RendererChoice::Auto)?;
    let obstacle = Some(Obstacle::build(&body.mesh, &renderer, &RenderOptions::default(), &WindingOptions::default())?);
    for t in grade3d::template::library::builtin().map_err(|(name, e)| format!("template {name}: {e}"))? {
        let g = grade3d::pipeline::grade(&t, &body, obstacle.as_ref(), "reference", &Default::default())?;
        let (panels, _) = grade3d::pattern::panels::cut(&t, &g.mesh.positions, &g.mesh.triangles, &g.lineage)?;
        for p in panels {
            let path = dir.join(format!("{}-{}.obj", t.name, p.name));
            let triangles: Vec<[u32; 3]> = p.triangles.iter().map(|t| t.map(|v| v.0)).collect();
            std::fs::write(&path, grade3d::io::obj::write_obj(&p.positions.raw, None, &triangles))?;
            println!("wrote {} ({} vertices, {} triangles)", path.display(), p.positions.len(), p.triangles.len());
        }
    }
    Ok(())
}

fn serve(cfg: grade3d::service::ServiceConfig) -> Result<(), Box<dyn std::error::Error>> {
    let addr = cfg.addr;
    let state = grade3d::service::AppState::open(cfg)?;
    state.start_gpu();
    let rt = tokio::runtime::Runtime::new()?;
    rt.block_on(async move {
        state.start_background();
        let listener = tokio::net::TcpListener::bind(addr).await?;
        // the e2e tests and the README read this line for the bound address
        tracing::info!(addr = %listener.local_addr()?, "listening");
        println!("listening on http://{}", listener.local_addr()?);
        axum::serve(listener, grade3d::service::app(state)).with_graceful_shutdown(shutdown()).await?;
        tracing::info!("shut down");
        Ok::<(), Box<dyn std::error::Error>>(())
    })?;
    Ok(())
}

/// Resolves on Ctrl-C or SIGTERM (graceful shutdown: in-flight requests finish).
async fn shutdown() {
    let ctrl_c = async {
        let _ = tokio::signal::ctrl_c().await;
    };
    #[cfg(unix)]
    let term = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let term = std::future::pending::<()>();
    tokio::select! {
        () = ctrl_c => {},
        () = term => {},
    }
}
