//! The page's files, embedded in the binary from `apps/studio/static/` (three.js vendored under
//! `vendor/three/` with its licence).

use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use rust_embed::RustEmbed;

/// The embedded static folder.
#[derive(RustEmbed)]
#[folder = "static/"]
pub struct Assets;

/// The embedded file at `path` with its content type, or 404.
pub fn serve(path: &str) -> Response {
    match Assets::get(path) {
        Some(file) => {
            let mime = mime_guess::from_path(path).first_or_octet_stream();
            (
                [
                    (header::CONTENT_TYPE, mime.as_ref().to_owned()),
                    (header::CACHE_CONTROL, "no-cache".to_owned()),
                ],
                file.data.into_owned(),
            )
                .into_response()
        }
        None => (StatusCode::NOT_FOUND, format!("no file {path}")).into_response(),
    }
}
