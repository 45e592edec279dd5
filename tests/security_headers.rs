//! Security headers on every kind of response: pages (which carry tokens in their URLs), files,
//! API answers, API errors and unknown paths, from the web UI on disk and inside the binary.
//! And the pages themselves keep to the policy: no inline scripts or styles for it to block.

use crate::support::server::{TOKEN, root, state};
use axum::body::Body;
use axum::http::{HeaderMap, Request, header};
use dualrep::http::app;
use tower::ServiceExt;

/// A request of each kind the server answers.
const URIS: [&str; 7] = [
    "/",
    "/train/abc123?token=secret",
    "/review/abc123?token=secret",
    "/js/trainer.js",
    "/api/tasks",
    "/api/sessions",     // 401 without the token
    "/api/nothing-here", // 404
];

/// The headers of every response in [`URIS`], from a router serving `web/` from disk and one
/// serving the copy inside the binary.
async fn every_response_headers() -> Vec<(String, HeaderMap)> {
    let dir = tempfile::tempdir().unwrap();
    let on_disk = app(state(dir.path()).await);
    let mut shipped_state = state(dir.path()).await;
    shipped_state.web_dir = None;
    let shipped = app(shipped_state);
    let mut out = Vec::new();
    for (which, router) in [("web dir", on_disk), ("shipped", shipped)] {
        for uri in URIS {
            let request = Request::get(uri).body(Body::empty()).unwrap();
            let response = router.clone().oneshot(request).await.unwrap();
            out.push((
                format!("{which} {uri} ({})", response.status()),
                response.headers().clone(),
            ));
        }
    }
    // And a researcher's successful API call.
    let request = Request::get("/api/sessions")
        .header(header::AUTHORIZATION, format!("Bearer {TOKEN}"))
        .body(Body::empty())
        .unwrap();
    let response = app(state(dir.path()).await).oneshot(request).await.unwrap();
    out.push((
        "GET /api/sessions with the token".into(),
        response.headers().clone(),
    ));
    out
}

fn value<'a>(headers: &'a HeaderMap, name: &header::HeaderName, what: &str) -> &'a str {
    headers
        .get(name)
        .unwrap_or_else(|| panic!("{what}: no {name} header"))
        .to_str()
        .unwrap()
}

#[tokio::test]
async fn every_response_sends_no_referrer() {
    for (what, headers) in every_response_headers().await {
        assert_eq!(
            value(&headers, &header::REFERRER_POLICY, &what),
            "no-referrer",
            "{what}"
        );
    }
}

#[tokio::test]
async fn every_response_forbids_framing_and_foreign_or_inline_scripts() {
    for (what, headers) in every_response_headers().await {
        let csp = value(&headers, &header::CONTENT_SECURITY_POLICY, &what);
        let directives: Vec<&str> = csp.split(';').map(str::trim).collect();
        assert!(
            directives.contains(&"frame-ancestors 'none'"),
            "{what}: {csp}"
        );
        assert!(directives.contains(&"script-src 'self'"), "{what}: {csp}");
        assert!(
            !csp.contains("unsafe-inline") && !csp.contains("unsafe-eval"),
            "{what}: {csp}"
        );
    }
}

#[tokio::test]
async fn every_response_forbids_mime_sniffing() {
    for (what, headers) in every_response_headers().await {
        assert_eq!(
            value(&headers, &header::X_CONTENT_TYPE_OPTIONS, &what),
            "nosniff",
            "{what}"
        );
    }
}

/// The policy allows no inline script or style: a page that had one would break under it
/// (the browser tests would see the violation; this says which page and where, at once).
#[test]
fn the_pages_have_no_inline_scripts_styles_or_handlers() {
    for page in ["index.html", "train.html", "review.html"] {
        let html = std::fs::read_to_string(root().join("web").join(page)).unwrap();
        for (n, line) in html.lines().enumerate() {
            let at = format!("web/{page}:{}: {line}", n + 1);
            assert!(!line.contains("<style"), "an inline <style>: {at}");
            assert!(!line.contains(" style="), "an inline style attribute: {at}");
            if line.contains("<script") {
                assert!(line.contains(" src="), "an inline <script>: {at}");
            }
            for handler in [
                " onclick=",
                " onload=",
                " oninput=",
                " onchange=",
                " onsubmit=",
            ] {
                assert!(!line.contains(handler), "an inline event handler: {at}");
            }
        }
    }
}
