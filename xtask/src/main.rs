//! `cargo xtask data …`: regenerates the data the repository ships from the
//! sources in `../shared` (issue #16: data generation moved out of the
//! `grade3d` binary). Each command writes files; none runs at service time.
//!
//! - `data mannequin`: `templates/mannequin/hm08.bin.gz` from the MakeHuman folder
//! - `data templates`: the built-in garment templates on the reference body
//! - `data garments`: MakeHuman's dense garment surfaces into `fixtures/garments`, and the
//!   A-line skirt's curves and surface (issue #18 item 5)
//! - `data fixtures`: `fixtures/bodies` (8 bodies) and `fixtures/astm` (12 ASTM sizes)

mod makehuman;

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// The base size of the ASTM fixtures' graded run (`data fixtures`; `tests/pattern.rs` grades it with this base).
const ASTM_BASE_SIZE: &str = "8";

#[derive(Parser)]
#[command(name = "xtask", about = "grade3d's data generators")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Regenerate shipped data from ../shared sources.
    Data {
        #[command(subcommand)]
        what: DataCommand,
    },
}

#[derive(Subcommand)]
enum DataCommand {
    /// Rebuild templates/mannequin/hm08.bin.gz from the MakeHuman folder.
    Mannequin {
        /// The MakeHuman hm08 folder.
        #[arg(long, default_value = "../shared/makehuman")]
        makehuman: PathBuf,
        /// Output file.
        #[arg(long, default_value = "templates/mannequin/hm08.bin.gz")]
        out: PathBuf,
    },
    /// Rebuild the built-in garment templates (templates/garments/*.json) on the reference body.
    Templates {
        /// Output folder.
        #[arg(long, default_value = "templates/garments")]
        dir: PathBuf,
    },
    /// Extract MakeHuman's dense garment surfaces (helper-skirt, helper-tights) into fixtures/garments.
    Garments {
        /// The MakeHuman hm08 folder.
        #[arg(long, default_value = "../shared/makehuman")]
        makehuman: PathBuf,
        /// Output folder.
        #[arg(long, default_value = "fixtures/garments")]
        dir: PathBuf,
    },
    /// Rebuild fixtures/bodies (8 bodies) and fixtures/astm (12 ASTM D5585 sizes).
    Fixtures {
        /// The fixtures folder.
        #[arg(long, default_value = "fixtures")]
        dir: PathBuf,
    },
}

fn main() -> ExitCode {
    let Cli { command: Command::Data { what } } = Cli::parse();
    match run(what) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(what: DataCommand) -> Result<(), Box<dyn std::error::Error>> {
    match what {
        DataCommand::Mannequin { makehuman, out } => {
            let data = makehuman::from_makehuman(&makehuman)?;
            let bytes = grade3d_core::mannequin::data::encode(&data);
            std::fs::write(&out, &bytes)?;
            println!(
                "wrote {} ({} bytes): {} vertices, {} triangles, {} targets, {} rings",
                out.display(),
                bytes.len(),
                data.positions.len(),
                data.triangles.len(),
                data.targets.len(),
                data.rings.len()
            );
        }
        DataCommand::Fixtures { dir } => write_fixtures(&dir)?,
        DataCommand::Templates { dir } => {
            std::fs::create_dir_all(&dir)?;
            for t in grade3d_core::template::library::author_all()? {
                let path = dir.join(format!("{}.json", t.name));
                std::fs::write(&path, t.to_json())?;
                println!("wrote {} ({} nodes, {} faces)", path.display(), t.nodes.len(), t.faces.len());
            }
        }
        DataCommand::Garments { makehuman, dir } => {
            std::fs::create_dir_all(&dir)?;
            for group in ["helper-skirt", "helper-tights"] {
                let (pos, tris) = makehuman::obj_group(&makehuman, group)?;
                let raw: Vec<[u64; 3]> = tris.iter().map(|t| t.map(u64::from)).collect();
                let mesh = grade3d_core::geom::mesh::TriMesh::from_raw(pos, &raw)?;
                let glb = grade3d_io::gltf::write_glb(&mesh, None, &[], "grade3d fixtures (MakeHuman hm08, CC0)")?;
                let path = dir.join(format!("{group}.glb"));
                std::fs::write(&path, glb)?;
                println!(
                    "wrote {} ({} vertices, {} triangles)",
                    path.display(),
                    mesh.vertex_count(),
                    mesh.face_count()
                );
            }
            // issue #18 item 5: the library's A-line skirt as drawn (route 2's curves) and as
            // sampled (route 1's garment, one group per panel) on the reference body
            use grade3d_core::template::drawn;
            let body = grade3d_core::template::library::reference_body()?;
            let (a_line, dress) = (drawn::ALineOptions::default(), drawn::ShiftDressOptions::default());
            let styles = [
                (
                    "a-line-skirt",
                    drawn::a_line_skirt_curves(&body, &a_line)?,
                    drawn::a_line_skirt_surface(&body, &a_line)?,
                ),
                ("shift-dress", drawn::shift_dress_curves(&body, &dress)?, drawn::shift_dress_surface(&body, &dress)?),
                // the library's shift dress
                (
                    "princess-dress",
                    drawn::shift_dress_curves(&body, &drawn::ShiftDressOptions::princess())?,
                    drawn::shift_dress_surface(&body, &drawn::ShiftDressOptions::princess())?,
                ),
                // the T-shirt: the princess bodice cut at the hip, set-in sleeves sewn into its armholes
                (
                    "t-shirt",
                    drawn::t_shirt_curves(&body, &drawn::TShirtOptions::default())?,
                    drawn::t_shirt_surface(&body, &drawn::TShirtOptions::default())?,
                ),
            ];
            for (name, curves, pieces) in styles {
                let path = dir.join(format!("{name}.curves.json"));
                std::fs::write(&path, serde_json::to_string_pretty(&curves)? + "\n")?;
                println!("wrote {} ({} patches)", path.display(), curves.len());
                let path = dir.join(format!("{name}.obj"));
                let header = format!("grade3d's {name} on its reference body (metres; `cargo xtask data garments`)");
                std::fs::write(&path, grade3d_io::obj::write_obj_panels(&pieces, &header))?;
                println!("wrote {} ({} pieces)", path.display(), pieces.len());
            }
        }
    }
    Ok(())
}

fn write_body(
    dir: &std::path::Path,
    name: &str,
    mesh: &grade3d_core::geom::mesh::TriMesh,
    lm: &grade3d_core::body::derive::Landmarks,
) -> Result<(), Box<dyn std::error::Error>> {
    let glb = grade3d_io::gltf::write_glb(mesh, None, &[], "grade3d fixtures")?;
    std::fs::write(dir.join(format!("{name}.glb")), glb)?;
    std::fs::write(dir.join(format!("{name}.landmarks.json")), grade3d_io::landmarks::write_landmarks(lm))?;
    Ok(())
}

fn write_fixtures(dir: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    use grade3d_core::mannequin::{fit, fixtures, landmarks, model::BodyModel, size_chart};
    let model = BodyModel::embedded()?;
    let bodies = dir.join("bodies");
    std::fs::create_dir_all(&bodies)?;
    let mut manifest = serde_json::Map::new();
    for f in fixtures::fixture_bodies() {
        let mesh = model.build(&f.params)?;
        let lm = landmarks::hm08_landmarks(model, &mesh, &Default::default())?;
        write_body(&bodies, f.name, &mesh, &lm)?;
        manifest.insert(f.name.to_owned(), serde_json::to_value(&f.params)?);
        println!("wrote {}", f.name);
    }
    std::fs::write(bodies.join("manifest.json"), serde_json::to_string_pretty(&manifest)? + "\n")?;
    let astm = dir.join("astm");
    std::fs::create_dir_all(&astm)?;
    let chart_text = std::fs::read_to_string(dir.join("size-charts/astm-d5585-11-misses-partial.csv"))?;
    let chart = size_chart::parse_csv(&chart_text, &Default::default())?;
    let mut report = serde_json::Map::new();
    // one graded run from the sample size 8 (tests/pattern.rs grades it with base size 8)
    let base = chart.rows.iter().position(|r| r.size == ASTM_BASE_SIZE).ok_or("the ASTM chart has no size 8")?;
    let fits = fit::fit_chart(model, &chart.rows, base, &fit::FitOptions::default())?;
    for (row, fitted) in chart.rows.iter().zip(fits) {
        let lm = landmarks::hm08_landmarks(model, &fitted.body.mesh, &Default::default())?;
        write_body(&astm, &format!("size-{}", row.size), &fitted.body.mesh, &lm)?;
        let residuals: serde_json::Map<String, serde_json::Value> = fitted
            .residuals
            .iter()
            .map(|(k, r)| (k.as_str().to_owned(), serde_json::json!({"target_mm": r.target_m * 1e3, "achieved_mm": r.achieved_m * 1e3, "error_mm": r.error_mm()})))
            .collect();
        report.insert(row.size.clone(), serde_json::json!({"params": fitted.params, "profile_scales": fitted.profile_scales.iter().map(|(k, v)| (k.as_str().to_owned(), *v)).collect::<std::collections::BTreeMap<_, _>>(), "residuals": residuals}));
        println!("wrote size {}", row.size);
    }
    std::fs::write(astm.join("fit-report.json"), serde_json::to_string_pretty(&report)? + "\n")?;
    Ok(())
}
