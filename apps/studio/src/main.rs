//! `studio`: the planner in a browser. Serves the page and its API on localhost (see
//! `apps/studio/API.md`); everything else is in the library (tissue-studio).

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::process::ExitCode;

use clap::Parser;
use tissue_cli::Exit;

/// Plan a tissue-expander insertion in the browser: pick the patient, place and size the
/// implant, run and see the result. Serves on 127.0.0.1 (this computer only) unless --host is
/// given, and prints the address to open.
#[derive(Debug, Parser)]
#[command(name = "studio", version, after_long_help = Exit::help_section(&[
    (Exit::Output, "the temporary folder cannot be made"),
    (Exit::Failure, "the server cannot start or listen (another --port?) or stopped"),
]))]
struct Cli {
    /// The address to listen on; another than 127.0.0.1 lets other computers reach the studio.
    #[arg(long, default_value_t = IpAddr::V4(Ipv4Addr::LOCALHOST))]
    host: IpAddr,
    /// The port; 0 picks a free one.
    #[arg(long, default_value_t = 8000)]
    port: u16,
}

fn main() -> ExitCode {
    tissue_cli::reset_sigpipe();
    let cli = Cli::parse();
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let runtime = match tokio::runtime::Runtime::new() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("studio: error: cannot start the async runtime: {e}");
            return Exit::Failure.into();
        }
    };
    match runtime.block_on(serve(SocketAddr::new(cli.host, cli.port))) {
        Ok(()) => ExitCode::SUCCESS,
        Err((exit, message)) => {
            eprintln!("studio: error: {message}");
            exit.into()
        }
    }
}

/// Serves until Ctrl-C; a failure is its exit code and message.
async fn serve(addr: SocketAddr) -> Result<(), (Exit, String)> {
    let studio = tissue_studio::Studio::new().map_err(|e| {
        (
            Exit::Output,
            format!("cannot make the temporary folder: {e}"),
        )
    })?;
    let listener = tokio::net::TcpListener::bind(addr).await.map_err(|e| {
        (
            Exit::Failure,
            format!("cannot listen on {addr}: {e}; give another --port (0 picks a free one)"),
        )
    })?;
    let local = listener
        .local_addr()
        .map_err(|e| (Exit::Failure, format!("cannot read the address: {e}")))?;
    println!("studio: http://{local}/");
    let app = tissue_studio::router(studio.clone());
    let stopping = studio.clone();
    let served = axum::serve(listener, app)
        .with_graceful_shutdown(async move {
            let _ = tokio::signal::ctrl_c().await;
            // Sockets close and the running job is cancelled, so that the server can stop.
            stopping.shutdown();
        })
        .await;
    studio.shutdown();
    served.map_err(|e| (Exit::Failure, format!("the server stopped: {e}")))
}
