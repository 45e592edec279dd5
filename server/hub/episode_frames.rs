//! The frames of the episode a session is playing, kept by its owner and written to the data
//! dir when the episode ends, for replay in the review page.

/// Frames of the episode being played, in the shape of a query clip.
#[derive(Default)]
pub(super) struct EpisodeFrames {
    episode: Option<u64>,
    geometry: Option<crate::sim::Geometry>,
    frames: Vec<crate::sim::RenderState>,
}

impl EpisodeFrames {
    pub fn push(&mut self, frame: &crate::session::Frame, geometry: Option<&crate::sim::Geometry>) {
        if self.episode != Some(frame.episode) {
            self.episode = Some(frame.episode);
            self.frames.clear();
            self.geometry = None;
        }
        if self.geometry.is_none() {
            self.geometry = frame.geometry.clone().or_else(|| geometry.cloned());
        }
        self.frames.push(frame.state.clone());
    }

    /// The frames of `episode`, if they were streamed.
    pub fn take(&mut self, episode: u64) -> Option<crate::session::Clip> {
        if self.episode != Some(episode) || self.frames.is_empty() {
            return None;
        }
        self.episode = None;
        Some(crate::session::Clip {
            geometry: self.geometry.take()?,
            frames: std::mem::take(&mut self.frames),
        })
    }
}

/// Write JSON atomically (a temporary file renamed into place); failures are logged.
pub(super) fn write_json(path: &std::path::Path, value: &impl serde::Serialize) {
    let result = (|| -> std::io::Result<()> {
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir)?;
        }
        let tmp = path.with_extension("json.tmp");
        std::fs::write(
            &tmp,
            serde_json::to_vec(value).map_err(std::io::Error::other)?,
        )?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        tracing::error!("writing {}: {e}", path.display());
    }
}
