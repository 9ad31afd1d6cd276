//! The integration tests of `tissue-studio` in one binary, a module per area (each module's own
//! doc says what it covers). Tests that must be alone in their process (allocation
//! counters, timing bounds) keep their own binaries beside `it/`.

mod api;
mod cases;
mod golden;
mod preview;
mod security;
mod trainer;

/// The port the in-process router believes it serves on (requests sent through `oneshot` carry
/// `Host: 127.0.0.1:PORT`).
const PORT: u16 = 8000;

/// The router for `studio` on loopback, with `Host: 127.0.0.1:8000` added to requests that have
/// none (a request through `oneshot` is not an HTTP/1.1 request off the wire).
fn app(studio: &tissue_studio::Studio) -> axum::Router {
    tissue_studio::router(studio.clone(), tissue_studio::Access::loopback(PORT)).layer(
        axum::middleware::map_request(|mut r: axum::extract::Request| async move {
            if !r.headers().contains_key("host") {
                let host = axum::http::HeaderValue::from_static("127.0.0.1:8000");
                r.headers_mut().insert("host", host);
            }
            r
        }),
    )
}

/// A studio served by [`tissue_studio::serve`] on a free local port with `limits`: the studio
/// (to shut down), its address, the server task.
async fn serve_with(
    limits: tissue_studio::Limits,
    require_token: bool,
) -> Result<
    (
        tissue_studio::Studio,
        std::net::SocketAddr,
        tokio::task::JoinHandle<()>,
        tissue_studio::Access,
    ),
    Box<dyn std::error::Error>,
> {
    let studio = tissue_studio::Studio::with_limits(limits)?;
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await?;
    let addr = listener.local_addr()?;
    let access = tissue_studio::Access::new(addr, Vec::new(), require_token)?;
    let server = tokio::spawn(tissue_studio::serve(
        listener,
        studio.clone(),
        access.clone(),
        std::future::pending(),
    ));
    Ok((studio, addr, server, access))
}

/// A studio served on a free local port with the default limits: the studio (to shut down), its
/// address, the server task.
async fn serve() -> Result<
    (
        tissue_studio::Studio,
        std::net::SocketAddr,
        tokio::task::JoinHandle<()>,
    ),
    Box<dyn std::error::Error>,
> {
    let (studio, addr, server, _) = serve_with(tissue_studio::Limits::default(), false).await?;
    Ok((studio, addr, server))
}
