//! The integration tests of `tissue-studio` in one binary, a module per area (each module's own
//! doc says what it covers). Tests that must be alone in their process (allocation
//! counters, timing bounds) keep their own binaries beside `it/`.

mod api;
mod trainer;

/// A studio served on a free local port: the studio (to shut down), its address, the server task.
async fn serve() -> Result<
    (
        tissue_studio::Studio,
        std::net::SocketAddr,
        tokio::task::JoinHandle<std::io::Result<()>>,
    ),
    Box<dyn std::error::Error>,
> {
    let studio = tissue_studio::Studio::new()?;
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await?;
    let addr = listener.local_addr()?;
    let app = tissue_studio::router(studio.clone());
    let server = tokio::spawn(async move { axum::serve(listener, app).await });
    Ok((studio, addr, server))
}
