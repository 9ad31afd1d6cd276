//! Serving the router on a listener with limits on time and connections, and a stop that always
//! ends ([`serve`]).
//!
//! axum's own `serve` sets no timer, so a request whose headers or body never finish was held for
//! as long as the sender liked. Here every connection is hyper's HTTP/1 with:
//! - a **header-read timeout** ([`Limits::header_timeout`]): the headers of a request, and the
//!   wait for the next one on a kept-alive connection, end within it or the connection is
//!   dropped;
//! - a **body deadline** ([`DeadlineBody`]): no byte of a body for [`Limits::body_idle`], or a
//!   body still unfinished after [`Limits::body_total`], fails the read (the handler answers 408
//!   and the connection is dropped);
//! - at most [`Limits::max_connections`] connections at once (more wait in the kernel's backlog);
//! - on stop: the listener closes, the studio shuts down (its job is cancelled, its sockets told
//!   to close, its temporary folder removed), open connections are asked to finish, and after
//!   [`Limits::shutdown_grace`] `serve` returns whatever they do.
//!
//! WebSockets are taken over from hyper once upgraded; their sends have their own timeout
//! ([`Limits::send_timeout`], in `jobs.rs` and `trainer.rs`).

use std::future::Future;
use std::pin::{pin, Pin};
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;

use axum::body::{Body, Bytes};
use http_body::{Frame, SizeHint};
use hyper::body::Incoming;
use hyper_util::rt::{TokioIo, TokioTimer};
use tokio::net::TcpListener;
use tokio::sync::{watch, Semaphore};
use tokio::time::{Instant, Sleep};
use tower::ServiceExt;

use crate::access::Access;
use crate::state::{Limits, Studio};

/// Why a request body was cut off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum BodyTimeout {
    /// No byte came for this long.
    #[error("no data came for {0:?}: the upload stalled")]
    Idle(Duration),
    /// The body was still unfinished after this long.
    #[error("the upload took longer than {0:?}")]
    Total(Duration),
}

/// A request body that fails when it stalls or takes too long (see the module doc).
pub struct DeadlineBody {
    inner: Incoming,
    idle: Duration,
    total: Duration,
    idle_timer: Pin<Box<Sleep>>,
    total_timer: Pin<Box<Sleep>>,
}

impl DeadlineBody {
    /// `inner` with the deadlines of `limits`, counted from now.
    pub fn new(inner: Incoming, limits: &Limits) -> DeadlineBody {
        let now = Instant::now();
        DeadlineBody {
            inner,
            idle: limits.body_idle,
            total: limits.body_total,
            idle_timer: Box::pin(tokio::time::sleep_until(now + limits.body_idle)),
            total_timer: Box::pin(tokio::time::sleep_until(now + limits.body_total)),
        }
    }
}

impl http_body::Body for DeadlineBody {
    type Data = Bytes;
    type Error = Box<dyn std::error::Error + Send + Sync>;

    fn poll_frame(
        self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<Frame<Bytes>, Self::Error>>> {
        let this = self.get_mut();
        match Pin::new(&mut this.inner).poll_frame(cx) {
            Poll::Ready(frame) => {
                let next = Instant::now() + this.idle;
                this.idle_timer.as_mut().reset(next);
                Poll::Ready(frame.map(|f| f.map_err(Into::into)))
            }
            Poll::Pending => {
                if this.total_timer.as_mut().poll(cx).is_ready() {
                    return Poll::Ready(Some(Err(Box::new(BodyTimeout::Total(this.total)))));
                }
                if this.idle_timer.as_mut().poll(cx).is_ready() {
                    return Poll::Ready(Some(Err(Box::new(BodyTimeout::Idle(this.idle)))));
                }
                Poll::Pending
            }
        }
    }

    fn is_end_stream(&self) -> bool {
        self.inner.is_end_stream()
    }

    fn size_hint(&self) -> SizeHint {
        self.inner.size_hint()
    }
}

/// Serves the studio's router for `access` on `listener` until `stop` resolves, then stops as
/// the module doc says. Returns when every connection has ended or the grace has passed.
pub async fn serve(
    listener: TcpListener,
    studio: Studio,
    access: Access,
    stop: impl Future<Output = ()>,
) {
    let limits = studio.limits().clone();
    let app = crate::router(studio.clone(), access);
    let slots = Arc::new(Semaphore::new(limits.max_connections));
    let (closing_tx, closing) = watch::channel(false);
    let mut stop = pin!(stop);
    loop {
        let permit = tokio::select! {
            p = Arc::clone(&slots).acquire_owned() => match p {
                Ok(p) => p,
                Err(_) => break,
            },
            () = &mut stop => break,
        };
        let stream = tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok((stream, _)) => stream,
                Err(e) => {
                    // Out of file descriptors and the like: wait a little rather than spin.
                    tracing::warn!("accept failed: {e}");
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
            () = &mut stop => break,
        };
        let _ = stream.set_nodelay(true);
        let app = app.clone();
        let body_limits = limits.clone();
        let service = hyper::service::service_fn(move |request: hyper::Request<Incoming>| {
            let request = request.map(|b| Body::new(DeadlineBody::new(b, &body_limits)));
            app.clone().oneshot(request)
        });
        let mut builder = hyper::server::conn::http1::Builder::new();
        builder
            .timer(TokioTimer::new())
            .header_read_timeout(limits.header_timeout);
        let mut closing = closing.clone();
        tokio::spawn(async move {
            let mut conn = pin!(builder
                .serve_connection(TokioIo::new(stream), service)
                .with_upgrades());
            let closed = tokio::select! {
                _ = conn.as_mut() => true,
                r = closing.wait_for(|c| *c) => { drop(r); false }
            };
            if !closed {
                conn.as_mut().graceful_shutdown();
                let _ = conn.await;
            }
            drop(permit);
        });
    }
    drop(listener);
    // The job is cancelled, the sockets close, the temporary folder goes.
    studio.shutdown();
    closing_tx.send_replace(true);
    let all = u32::try_from(limits.max_connections).unwrap_or(u32::MAX);
    let drained = tokio::time::timeout(limits.shutdown_grace, slots.acquire_many(all)).await;
    if drained.is_err() {
        tracing::warn!(
            "connections still open {:?} after the stop: stopping anyway",
            limits.shutdown_grace
        );
    }
}

/// Sends `message` on `socket` unless the peer does not take it within `limit` (a tab that stopped
/// reading fills the kernel's buffers, and a send would wait for ever); whether it was sent.
pub(crate) async fn send_within(
    socket: &mut axum::extract::ws::WebSocket,
    message: axum::extract::ws::Message,
    limit: Duration,
) -> bool {
    matches!(
        tokio::time::timeout(limit, socket.send(message)).await,
        Ok(Ok(()))
    )
}
