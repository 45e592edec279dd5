//! Security headers on every response. Trainer and review pages carry their session's token in
//! the URL (`/train/{id}?token=...`), so a page must not leak its URL to other sites
//! (`Referrer-Policy`), must not be framed by one (`frame-ancestors`), and must run only the
//! scripts this server ships (`script-src 'self'`): an injected script could read the token.

use axum::Router;
use axum::http::{HeaderName, HeaderValue, header};
use tower_http::set_header::SetResponseHeaderLayer;

/// What the web UI (`web/`) needs and nothing more:
///
/// - scripts and styles only as files from this server (no inline `<script>`, `<style>` or
///   `style="..."` in the pages; scripts may still set `element.style`, which CSP allows);
/// - `connect-src 'self'`: the API's `fetch` and the trainer websocket on this host (CSP Level 3
///   lets `'self'` match `ws:`/`wss:` to the same host);
/// - `img-src 'self' data: blob:`: a remote env's frames arrive as base64 `data:` URLs;
/// - downloads through `blob:` links are navigations, which `default-src` does not govern.
pub const CONTENT_SECURITY_POLICY: &str = "default-src 'self'; script-src 'self'; \
     style-src 'self'; img-src 'self' data: blob:; connect-src 'self'; object-src 'none'; \
     base-uri 'none'; form-action 'self'; frame-ancestors 'none'";

/// Add the headers to every response of `router` (API, websocket refusals, pages, files).
/// `overriding`: a handler cannot weaken them.
pub fn add<S: Clone + Send + Sync + 'static>(router: Router<S>) -> Router<S> {
    let headers: [(HeaderName, &'static str); 3] = [
        (header::REFERRER_POLICY, "no-referrer"),
        (header::CONTENT_SECURITY_POLICY, CONTENT_SECURITY_POLICY),
        (header::X_CONTENT_TYPE_OPTIONS, "nosniff"),
    ];
    headers.into_iter().fold(router, |router, (name, value)| {
        router.layer(SetResponseHeaderLayer::overriding(
            name,
            HeaderValue::from_static(value),
        ))
    })
}
