//! What the binary carries: the web UI and the shipped experts, so that `dualrep serve` works
//! from any directory and after `cargo install --path .`. `--web-dir` and `--models-dir` still
//! point the server at files on disk (for development).
//!
//! Every build embeds the files at compile time, debug builds too (rust-embed's `debug-embed`):
//! by default a debug build would read them at run time from the absolute path of the checkout
//! that compiled it, and with CI's clones sharing one target directory a later `cargo test` in
//! another checkout could serve a deleted clone's files (nothing: every page 404s) or a stale
//! one's. `build.rs` rebuilds when a file in `web/` or `models/` changes or is added; to edit the
//! pages without rebuilding, serve them with `--web-dir web`.

use std::borrow::Cow;

use rust_embed::RustEmbed;

use crate::sim::Task;

#[derive(RustEmbed)]
#[folder = "web/"]
#[exclude = "README.md"]
struct WebFiles;

#[derive(RustEmbed)]
#[folder = "models/"]
#[include = "*.safetensors"]
struct Experts;

/// A web UI file by its path under `web/` (`index.html`, `js/trainer.js`): its bytes and MIME
/// type.
pub fn web_file(path: &str) -> Option<(Cow<'static, [u8]>, String)> {
    let file = WebFiles::get(path)?;
    let mime = file.metadata.mimetype().to_string();
    Some((file.data, mime))
}

/// The shipped expert of `task` (`models/<task>.safetensors`), as `dualrep expert` wrote it.
pub fn expert(task: Task) -> Option<Cow<'static, [u8]>> {
    Experts::get(&format!("{task}.safetensors")).map(|f| f.data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_web_ui_and_every_tasks_expert_are_shipped() {
        for page in [
            "index.html",
            "train.html",
            "review.html",
            "js/trainer.js",
            "css/base.css",
        ] {
            let (bytes, mime) = web_file(page).unwrap_or_else(|| panic!("{page} is not shipped"));
            assert!(!bytes.is_empty(), "{page}");
            let want = if page.ends_with(".html") {
                "text/html"
            } else if page.ends_with(".js") {
                "javascript"
            } else {
                "text/css"
            };
            assert!(mime.contains(want), "{page}: {mime}");
        }
        assert!(web_file("README.md").is_none() && web_file("nope.html").is_none());
        for task in Task::ALL {
            let bytes = expert(task).unwrap_or_else(|| panic!("no shipped expert for {task}"));
            crate::rl::Sac::from_safetensors(&bytes).unwrap();
        }
    }
}
