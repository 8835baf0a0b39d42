//! `grade3d` command line: the service and the data tools.

use std::net::SocketAddr;
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
    Serve {
        /// Address to listen on.
        #[arg(long, env = "GRADE3D_ADDR", default_value = "127.0.0.1:8080")]
        addr: SocketAddr,
    },
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
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(tracing_subscriber::EnvFilter::try_from_default_env().unwrap_or_else(|_| "info".into()))
        .init();
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<(), Box<dyn std::error::Error>> {
    match cli.command {
        Command::Serve { addr } => {
            let rt = tokio::runtime::Runtime::new()?;
            rt.block_on(async move {
                let listener = tokio::net::TcpListener::bind(addr).await?;
                tracing::info!(%addr, "listening");
                axum::serve(listener, grade3d::service::app(grade3d::service::AppState::default()))
                    .with_graceful_shutdown(async {
                        let _ = tokio::signal::ctrl_c().await;
                    })
                    .await?;
                Ok::<(), Box<dyn std::error::Error>>(())
            })?;
        }
        Command::Data {
            what: DataCommand::Mannequin { makehuman, out },
        } => {
            let data = grade3d::mannequin::data::from_makehuman(&makehuman)?;
            let bytes = grade3d::mannequin::data::encode(&data);
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
    }
    Ok(())
}
