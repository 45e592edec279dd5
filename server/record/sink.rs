//! Opening the `RecordingStream` the options ask for: an `.rrd` file, a live viewer over gRPC,
//! or both through one stream teed into two sinks (`set_sinks`), so that file and viewer get
//! the same chunks.

use anyhow::Context;
use rerun::external::re_uri::ProxyUri;
use rerun::sink::{FileSink, GrpcSink};
use rerun::{ApplicationId, RecordingStream, RecordingStreamBuilder};

use super::RecordingOptions;

/// The stream for `options`, or `None` when both file and viewer are off.
pub(super) fn open(
    application: &str,
    recording_name: &str,
    options: &RecordingOptions,
) -> anyhow::Result<Option<RecordingStream>> {
    if options.is_off() {
        return Ok(None);
    }
    let application = ApplicationId::try_from(application.to_owned())
        .with_context(|| format!("invalid Rerun application id {application:?}"))?;
    let builder = RecordingStreamBuilder::new(application)
        // The caller asked for a recording: the `RERUN` environment variable must not turn it
        // off silently.
        .enabled(true)
        .recording_id(recording_name)
        // `recording_id` stops the properties chunk; we want the name shown in the viewer.
        .recording_name(recording_name)
        .send_properties(true);
    // Validate the url before creating any file.
    let uri = options
        .connect
        .as_deref()
        .map(parse_proxy_url)
        .transpose()?;
    if let Some(path) = &options.path
        && let Some(parent) = path.parent().filter(|p| !p.as_os_str().is_empty())
    {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("creating {}", parent.display()))?;
    }
    let stream = match (&options.path, uri) {
        (None, None) => unreachable!("checked by is_off"),
        (Some(path), None) => builder
            .save(path)
            .with_context(|| format!("opening the recording {}", path.display()))?,
        (None, Some(uri)) => builder
            .connect_grpc_opts(uri.to_string())
            .with_context(|| format!("connecting to the Rerun viewer at {uri}"))?,
        (Some(path), Some(uri)) => {
            let file = FileSink::new(path)
                .with_context(|| format!("opening the recording {}", path.display()))?;
            builder
                .set_sinks((file, GrpcSink::new(uri)))
                .context("starting the recording")?
        }
    };
    Ok(Some(stream))
}

fn parse_proxy_url(url: &str) -> anyhow::Result<ProxyUri> {
    url.parse::<ProxyUri>().with_context(|| {
        format!("{url:?} is not a Rerun gRPC proxy url (like rerun+http://127.0.0.1:9876/proxy)")
    })
}
