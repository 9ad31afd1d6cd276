//! `studio`: the planner and the trainer in a browser. Serves the page and its API (see
//! `apps/studio/API.md`) on this computer, or with a token to others; everything else is in the
//! library (tissue-studio). `apps/studio/SECURITY.md` is the threat model.
#![allow(clippy::print_stdout, clippy::print_stderr)]

use std::net::{IpAddr, Ipv4Addr, SocketAddr};
use std::process::ExitCode;
use std::time::Duration;

use clap::Parser;
use tissue_cli::Exit;

/// Plan a tissue-expander insertion and train surgery in the browser. Serves on 127.0.0.1 (this
/// computer only) unless --host is given, and prints the address to open. Off loopback every
/// request needs the random token printed in that address; TLS belongs to a reverse proxy (see
/// the README).
#[derive(Debug, Parser)]
#[command(name = "studio", version, after_long_help = Exit::help_section(&[
    (Exit::Usage, "no --data given and this computer has no user data folder"),
    (Exit::Output, "the temporary folder or the case library cannot be made or opened"),
    (Exit::Failure, "the server cannot start or listen (another --port?) or stopped"),
]))]
struct Cli {
    /// The address to listen on. Another than loopback lets other computers reach the studio:
    /// it then makes a token that every request needs, printed in its address line.
    #[arg(long, default_value_t = IpAddr::V4(Ipv4Addr::LOCALHOST))]
    host: IpAddr,
    /// The port; 0 picks a free one.
    #[arg(long, default_value_t = 8000)]
    port: u16,
    /// A host name a reverse proxy passes on in `Host` (`studio.clinic.example`), besides
    /// 127.0.0.1, localhost and [::1]; repeatable. Implies the token.
    #[arg(long = "allowed-host", value_name = "NAME")]
    allowed_hosts: Vec<String>,
    /// Require the token on loopback too: on a computer other people log in to, where they could
    /// reach 127.0.0.1.
    #[arg(long)]
    require_token: bool,
    /// The case library's folder: the patients, their plans and results (patient data, made with
    /// mode 0700, its files 0600). Default: the platform's user data folder
    /// (`~/.local/share/tissue` on Linux).
    #[arg(long, value_name = "DIR")]
    data: Option<std::path::PathBuf>,
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
    let result = runtime.block_on(run(cli));
    // Tasks still blocked (a peer that stopped reading) do not hold the process.
    runtime.shutdown_timeout(Duration::from_millis(500));
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err((exit, message)) => {
            eprintln!("studio: error: {message}");
            exit.into()
        }
    }
}

/// Serves until Ctrl-C or SIGTERM; a failure is its exit code and message.
async fn run(cli: Cli) -> Result<(), (Exit, String)> {
    let addr = SocketAddr::new(cli.host, cli.port);
    let listener = tokio::net::TcpListener::bind(addr).await.map_err(|e| {
        (
            Exit::Failure,
            format!("cannot listen on {addr}: {e}; give another --port (0 picks a free one)"),
        )
    })?;
    let local = listener
        .local_addr()
        .map_err(|e| (Exit::Failure, format!("cannot read the address: {e}")))?;
    let access = tissue_studio::Access::new(local, cli.allowed_hosts, cli.require_token)
        .map_err(|e| (Exit::Failure, format!("cannot make the access token: {e}")))?;
    let data = match cli.data {
        Some(dir) => dir,
        None => tissue_cases::default_data_dir().map_err(|e| (Exit::Usage, e.to_string()))?,
    };
    let studio = tissue_studio::Studio::with_data(tissue_studio::Limits::default(), &data)
        .map_err(|e| (Exit::Output, e.to_string()))?;
    if !local.ip().is_loopback() {
        eprintln!(
            "studio: warning: listening on {local}, reachable from other computers: every \
             request needs the token in the address below; the connection is not encrypted, so \
             put a TLS reverse proxy in front of it (README: \"Serving to other computers\")"
        );
    }
    println!("studio: {}", access.address());
    let stopping = studio.clone();
    tissue_studio::serve(listener, studio, access, async move {
        stop_signal().await;
        // A second Ctrl-C or SIGTERM while the first stop waits: out now, the folder removed.
        tokio::spawn(async move {
            stop_signal().await;
            stopping.shutdown();
            eprintln!("studio: stopped at once (second signal)");
            std::process::exit(130);
        });
    })
    .await;
    Ok(())
}

/// Ctrl-C (SIGINT) or SIGTERM (what systemd, docker and `kill` send).
async fn stop_signal() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{signal, SignalKind};
        match signal(SignalKind::terminate()) {
            Ok(mut term) => {
                tokio::select! {
                    _ = tokio::signal::ctrl_c() => {}
                    _ = term.recv() => {}
                }
            }
            Err(_) => {
                let _ = tokio::signal::ctrl_c().await;
            }
        }
    }
    #[cfg(not(unix))]
    {
        let _ = tokio::signal::ctrl_c().await;
    }
}
