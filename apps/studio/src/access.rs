//! Who may use the server: the Host allow-list (DNS rebinding), the same-origin check on every
//! WebSocket upgrade and state-changing request (other web pages), the access token off this
//! computer, and the security headers on every response. `SECURITY.md` is the threat model.
//!
//! Order of the checks, for every request ([`guard`]):
//! 1. **Host.** The `Host` header (and an absolute request URI's authority) must name this
//!    server: `127.0.0.1`, `localhost`, `[::1]` or the bound address, with the bound port, or a
//!    name given with `--allowed-host`. Anything else is 421: a page served from
//!    `rebind.evil.example` that re-points its name at 127.0.0.1 reaches the socket but not the
//!    studio.
//! 2. **Origin.** A WebSocket upgrade or a request other than GET/HEAD that carries `Origin` must
//!    come from the origin its `Host` names (`Origin: null` is refused), and a browser's
//!    `Sec-Fetch-Site` must be `same-origin` or `none`: 403. Programs that send no `Origin`
//!    (scripts, the tests) are not browsers driven by another site, and pass.
//! 3. **Token** (only when the server can be reached other than through a loopback name): the
//!    request carries the token the server printed, as the `studio-token-PORT` cookie the page
//!    gets, `Authorization: Bearer TOKEN`, or `?token=TOKEN`; else 401. Opening a page with
//!    `?token=` sets the cookie (HttpOnly, SameSite=Strict) and redirects to the same page
//!    without it, so the token leaves the address bar and every later request of the page
//!    (fetches, the WebSockets, download links) carries it.

use std::net::{IpAddr, SocketAddr};
use std::sync::{Arc, OnceLock};

use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode};
use axum::middleware::Next;
use axum::response::{IntoResponse, Response};
use base64::Engine;
use sha2::Digest;

use crate::api::ApiError;
use crate::messages::ErrorKind;

/// Who may use the server: its address, the extra host names, and the token when one is needed.
#[derive(Clone)]
pub struct Access {
    bound: IpAddr,
    port: u16,
    allowed_hosts: Vec<String>,
    token: Option<String>,
}

impl std::fmt::Debug for Access {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // The token is a secret: never in a log line.
        f.debug_struct("Access")
            .field("bound", &self.bound)
            .field("port", &self.port)
            .field("allowed_hosts", &self.allowed_hosts)
            .field("token", &self.token.as_ref().map(|_| "…"))
            .finish()
    }
}

impl Access {
    /// A server on `127.0.0.1:port` reached through loopback names only: no token.
    pub fn loopback(port: u16) -> Access {
        Access {
            bound: IpAddr::V4(std::net::Ipv4Addr::LOCALHOST),
            port,
            allowed_hosts: Vec::new(),
            token: None,
        }
    }

    /// The access of a server bound to `bound`, also answering to `allowed_hosts` (names a
    /// reverse proxy passes on, `name` or `name:port`, any case). A token is made — 128 random
    /// bits — when the server can be reached other than through a loopback name: a bind other
    /// than loopback, any allowed host, or `require_token`.
    ///
    /// # Errors
    /// The operating system's random generator fails.
    pub fn new(
        bound: SocketAddr,
        allowed_hosts: Vec<String>,
        require_token: bool,
    ) -> Result<Access, getrandom::Error> {
        let needs = require_token || !bound.ip().is_loopback() || !allowed_hosts.is_empty();
        let token = if needs { Some(random_hex(16)?) } else { None };
        Ok(Access {
            bound: bound.ip(),
            port: bound.port(),
            allowed_hosts: allowed_hosts
                .into_iter()
                .map(|h| h.trim().to_ascii_lowercase())
                .filter(|h| !h.is_empty())
                .collect(),
            token,
        })
    }

    /// The token every request needs, when one does.
    pub fn token(&self) -> Option<&str> {
        self.token.as_deref()
    }

    /// The address to open, with the token when one is needed:
    /// `http://127.0.0.1:8000/` or `http://HOST:PORT/?token=…`.
    pub fn address(&self) -> String {
        let at = SocketAddr::new(self.bound, self.port);
        match &self.token {
            Some(t) => format!("http://{at}/?token={t}"),
            None => format!("http://{at}/"),
        }
    }

    /// The cookie that carries the token (per port, so two studios on one computer do not mix).
    pub fn cookie_name(&self) -> String {
        format!("studio-token-{}", self.port)
    }

    /// Whether `host` (a `Host` header's value or a URI's authority) names this server.
    pub fn host_allowed(&self, host: &str) -> bool {
        let host = host.trim().to_ascii_lowercase();
        if self.allowed_hosts.iter().any(|a| {
            a == &host
                || host
                    .rsplit_once(':')
                    .is_some_and(|(name, _)| name == a.as_str())
        }) {
            return true;
        }
        let Some((name, port)) = split_host(&host) else {
            return false;
        };
        if port != Some(self.port) {
            return false;
        }
        if name == "localhost" {
            return true;
        }
        // An address literal cannot be re-pointed by DNS: loopback ones, and the bound one (any
        // when the server listens on every interface, where the token guards the door).
        match name
            .trim_start_matches('[')
            .trim_end_matches(']')
            .parse::<IpAddr>()
        {
            Ok(ip) => ip.is_loopback() || ip == self.bound || self.bound.is_unspecified(),
            Err(_) => false,
        }
    }

    fn token_ok(&self, presented: &str) -> bool {
        self.token
            .as_deref()
            .is_some_and(|t| constant_time_eq(t.as_bytes(), presented.as_bytes()))
    }
}

/// `name` and its port from `name:port`, `[v6]:port`, `name`.
fn split_host(host: &str) -> Option<(&str, Option<u16>)> {
    if host.starts_with('[') {
        let end = host.find(']')?;
        let (name, rest) = host.split_at(end + 1);
        return match rest.strip_prefix(':') {
            Some(p) => Some((name, Some(p.parse().ok()?))),
            None if rest.is_empty() => Some((name, None)),
            None => None,
        };
    }
    match host.rsplit_once(':') {
        Some((name, p)) => Some((name, Some(p.parse().ok()?))),
        None => Some((host, None)),
    }
}

/// Compares two secrets in time that depends on their lengths only.
fn constant_time_eq(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).fold(0u8, |acc, (x, y)| acc | (x ^ y)) == 0
}

/// `bytes` random bytes from the operating system, as lowercase hex.
///
/// # Errors
/// The generator fails.
pub fn random_hex(bytes: usize) -> Result<String, getrandom::Error> {
    let mut raw = vec![0u8; bytes];
    getrandom::fill(&mut raw)?;
    Ok(raw.iter().map(|b| format!("{b:02x}")).collect())
}

fn refuse(status: StatusCode, kind: ErrorKind, message: String) -> Response {
    ApiError::new(status, kind, message).into_response()
}

/// Whether `request` opens a WebSocket.
fn is_upgrade(headers: &HeaderMap) -> bool {
    headers
        .get(header::UPGRADE)
        .and_then(|v| v.to_str().ok())
        .is_some_and(|v| v.eq_ignore_ascii_case("websocket"))
}

/// The middleware: Host, then Origin, then the token (see the module doc).
pub async fn guard(State(access): State<Arc<Access>>, request: Request, next: Next) -> Response {
    let headers = request.headers();
    let Some(host) = headers.get(header::HOST).and_then(|h| h.to_str().ok()) else {
        return refuse(
            StatusCode::BAD_REQUEST,
            ErrorKind::Usage,
            "a request needs a Host header".to_owned(),
        );
    };
    let authority_ok = request
        .uri()
        .authority()
        .is_none_or(|a| access.host_allowed(a.as_str()));
    if !access.host_allowed(host) || !authority_ok {
        return refuse(
            StatusCode::MISDIRECTED_REQUEST,
            ErrorKind::Forbidden,
            format!(
                "this studio answers only at its own address ({}); open that address, or start \
                 it with --allowed-host NAME for the name a reverse proxy passes on",
                Access::loopback(access.port).address()
            ),
        );
    }
    let changes = !matches!(*request.method(), Method::GET | Method::HEAD);
    if changes || is_upgrade(headers) {
        if let Some(origin) = headers.get(header::ORIGIN) {
            let same = origin.to_str().ok().is_some_and(|o| {
                let o = o.to_ascii_lowercase();
                let host = host.to_ascii_lowercase();
                o == format!("http://{host}") || o == format!("https://{host}")
            });
            if !same {
                return refuse(
                    StatusCode::FORBIDDEN,
                    ErrorKind::Forbidden,
                    "only the studio's own page may use it: this request came from another site"
                        .to_owned(),
                );
            }
        }
        let site = headers.get("sec-fetch-site").and_then(|v| v.to_str().ok());
        if site.is_some_and(|s| s != "same-origin" && s != "none") {
            return refuse(
                StatusCode::FORBIDDEN,
                ErrorKind::Forbidden,
                "only the studio's own page may use it: the browser says this request came from \
                 another site"
                    .to_owned(),
            );
        }
    }
    if access.token.is_some() {
        let from_query = query_token(request.uri().query());
        let presented = cookie_token(headers, &access.cookie_name())
            .or_else(|| bearer_token(headers))
            .or(from_query.clone());
        if !presented.as_deref().is_some_and(|t| access.token_ok(t)) {
            return refuse(
                StatusCode::UNAUTHORIZED,
                ErrorKind::Unauthorized,
                "this studio needs the token it printed when it started: open the address it \
                 printed (…/?token=…)"
                    .to_owned(),
            );
        }
        // A page opened with ?token=: keep it in a cookie and take it out of the address.
        if let Some(t) = from_query {
            let path = request.uri().path();
            if *request.method() == Method::GET && !path.starts_with("/api/") && access.token_ok(&t)
            {
                return token_redirect(&access, path, request.uri().query());
            }
        }
    }
    next.run(request).await
}

fn token_redirect(access: &Access, path: &str, query: Option<&str>) -> Response {
    let rest: Vec<&str> = query
        .unwrap_or("")
        .split('&')
        .filter(|kv| !kv.is_empty() && !kv.starts_with("token="))
        .collect();
    let location = if rest.is_empty() {
        path.to_owned()
    } else {
        format!("{path}?{}", rest.join("&"))
    };
    let cookie = format!(
        "{}={}; Path=/; HttpOnly; SameSite=Strict",
        access.cookie_name(),
        access.token.as_deref().unwrap_or("")
    );
    (
        StatusCode::SEE_OTHER,
        [(header::LOCATION, location), (header::SET_COOKIE, cookie)],
    )
        .into_response()
}

fn query_token(query: Option<&str>) -> Option<String> {
    query?
        .split('&')
        .find_map(|kv| kv.strip_prefix("token="))
        .map(str::to_owned)
}

fn cookie_token(headers: &HeaderMap, name: &str) -> Option<String> {
    headers
        .get_all(header::COOKIE)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .flat_map(|v| v.split(';'))
        .find_map(|kv| {
            let (k, v) = kv.trim().split_once('=')?;
            (k == name).then(|| v.to_owned())
        })
}

fn bearer_token(headers: &HeaderMap) -> Option<String> {
    let v = headers.get(header::AUTHORIZATION)?.to_str().ok()?;
    v.strip_prefix("Bearer ").map(|t| t.trim().to_owned())
}

/// The Content-Security-Policy: this server's own files only, no framing, and the pages' inline
/// import maps by their hashes.
pub fn content_security_policy() -> &'static str {
    static CSP: OnceLock<String> = OnceLock::new();
    CSP.get_or_init(|| {
        let mut hashes = Vec::new();
        for page in ["index.html", "planner.html", "trainer.html", "cases.html"] {
            let Some(file) = crate::assets::Assets::get(page) else {
                continue;
            };
            for script in inline_scripts(&String::from_utf8_lossy(&file.data)) {
                let digest = sha2::Sha256::digest(script.as_bytes());
                let hash = format!(
                    "'sha256-{}'",
                    base64::engine::general_purpose::STANDARD.encode(digest)
                );
                if !hashes.contains(&hash) {
                    hashes.push(hash);
                }
            }
        }
        format!(
            "default-src 'self'; script-src 'self' {}; img-src 'self' data: blob:; \
             object-src 'none'; base-uri 'none'; form-action 'self'; frame-ancestors 'none'",
            hashes.join(" ")
        )
    })
}

/// The text of every inline `<script>` (one without `src`) in `html`.
fn inline_scripts(html: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut rest = html;
    while let Some(start) = rest.find("<script") {
        let after = &rest[start..];
        let Some(open_end) = after.find('>') else {
            break;
        };
        let tag = &after[..open_end];
        let body = &after[open_end + 1..];
        let Some(close) = body.find("</script>") else {
            break;
        };
        if !tag.contains("src=") {
            out.push(&body[..close]);
        }
        rest = &body[close..];
    }
    out
}

/// The middleware that puts the security headers on every response, and `no-store` on the
/// API's (patient data stays out of the browser's disk cache).
pub async fn headers(request: Request, next: Next) -> Response {
    let api = request.uri().path().starts_with("/api/");
    let mut response = next.run(request).await;
    let h = response.headers_mut();
    if let Ok(csp) = HeaderValue::from_str(content_security_policy()) {
        h.insert(header::CONTENT_SECURITY_POLICY, csp);
    }
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    h.insert(
        header::REFERRER_POLICY,
        HeaderValue::from_static("no-referrer"),
    );
    h.insert(
        "cross-origin-opener-policy",
        HeaderValue::from_static("same-origin"),
    );
    h.insert(
        "cross-origin-resource-policy",
        HeaderValue::from_static("same-origin"),
    );
    if api {
        h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-store"));
    }
    response
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hosts_name_this_server_only() {
        let a = Access::loopback(8000);
        for ok in [
            "127.0.0.1:8000",
            "localhost:8000",
            "LOCALHOST:8000",
            "[::1]:8000",
        ] {
            assert!(a.host_allowed(ok), "{ok}");
        }
        for bad in [
            "rebind.evil.example:8000",
            "rebind.evil.example",
            "127.0.0.1:8001",
            "127.0.0.1",
            "localhost",
            "10.0.0.5:8000",
            "localhost.evil.example:8000",
            "[::1]",
            "",
            "127.0.0.1:80000",
        ] {
            assert!(!a.host_allowed(bad), "{bad}");
        }
        let lan = Access::new(
            "0.0.0.0:8000".parse().unwrap(),
            vec!["Studio.Clinic.example".into()],
            false,
        )
        .unwrap();
        assert!(lan.token().is_some_and(|t| t.len() == 32));
        assert!(lan.host_allowed("192.168.1.20:8000"));
        assert!(lan.host_allowed("studio.clinic.example"));
        assert!(lan.host_allowed("studio.clinic.example:443"));
        assert!(!lan.host_allowed("evil.example:8000"));
        assert!(lan.address().contains("?token="));
    }

    #[test]
    fn a_token_is_made_only_when_the_server_is_reachable_from_elsewhere() {
        let make = |s: &str, hosts: Vec<String>, r: bool| {
            Access::new(s.parse::<SocketAddr>().unwrap(), hosts, r).unwrap()
        };
        assert!(make("127.0.0.1:1", vec![], false).token().is_none());
        assert!(make("[::1]:1", vec![], false).token().is_none());
        assert!(make("127.0.0.1:1", vec![], true).token().is_some());
        assert!(make("127.0.0.1:1", vec!["a.example".into()], false)
            .token()
            .is_some());
        assert!(make("192.168.0.2:1", vec![], false).token().is_some());
        let (a, b) = (
            make("0.0.0.0:1", vec![], false),
            make("0.0.0.0:1", vec![], false),
        );
        assert_ne!(a.token(), b.token(), "tokens are random");
        assert!(!format!("{a:?}").contains(a.token().unwrap()));
    }

    #[test]
    fn the_policy_hashes_the_pages_import_maps() {
        let csp = content_security_policy();
        assert!(csp.starts_with("default-src 'self';"), "{csp}");
        assert!(csp.contains("frame-ancestors 'none'"), "{csp}");
        assert!(csp.contains("'sha256-"), "{csp}");
        assert_eq!(
            inline_scripts("<script src=\"/a.js\"></script><script type=\"importmap\">{}</script>"),
            ["{}"]
        );
    }
}
