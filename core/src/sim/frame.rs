//! A frame an environment rendered itself (an env in another process): encoded image bytes that
//! go to browsers as base64 inside the frame message and into the recording as they are.

use std::sync::Arc;

use base64::Engine;
use base64::engine::general_purpose::STANDARD;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The image formats a remote env may send: what browsers and the Rerun viewer both decode.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum MediaType {
    #[serde(rename = "image/png")]
    Png,
    #[serde(rename = "image/jpeg")]
    Jpeg,
}

impl MediaType {
    /// The format's MIME type, as browsers and Rerun name it.
    pub fn mime(self) -> &'static str {
        match self {
            MediaType::Png => "image/png",
            MediaType::Jpeg => "image/jpeg",
        }
    }

    /// The format from the protocol's `format` word (`png`, `jpeg`).
    pub fn from_format(word: &str) -> Option<Self> {
        match word {
            "png" => Some(MediaType::Png),
            "jpeg" | "jpg" => Some(MediaType::Jpeg),
            _ => None,
        }
    }

    /// Whether `bytes` start as this format's files do (a cheap check that the env sent what
    /// it announced).
    pub fn matches(self, bytes: &[u8]) -> bool {
        match self {
            MediaType::Png => bytes.starts_with(b"\x89PNG\r\n\x1a\n"),
            MediaType::Jpeg => bytes.starts_with(&[0xff, 0xd8, 0xff]),
        }
    }
}

/// One encoded image. Cloning shares the bytes (a clip holds thirty frames).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImageFrame {
    pub media_type: MediaType,
    pub width: u32,
    pub height: u32,
    /// The encoded file (PNG or JPEG), base64 in JSON.
    #[serde(serialize_with = "to_base64", deserialize_with = "from_base64")]
    pub data: Arc<[u8]>,
}

fn to_base64<S: Serializer>(bytes: &Arc<[u8]>, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&STANDARD.encode(bytes))
}

fn from_base64<'de, D: Deserializer<'de>>(d: D) -> Result<Arc<[u8]>, D::Error> {
    let text = String::deserialize(d)?;
    STANDARD
        .decode(text)
        .map(Arc::from)
        .map_err(serde::de::Error::custom)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frame_round_trips_through_json_as_base64() {
        let frame = ImageFrame {
            media_type: MediaType::Png,
            width: 2,
            height: 1,
            data: Arc::from(&b"\x89PNG\r\n\x1a\nrest"[..]),
        };
        let json = serde_json::to_value(&frame).unwrap();
        assert_eq!(json["media_type"], "image/png");
        assert_eq!(json["data"], "iVBORw0KGgpyZXN0");
        assert_eq!(serde_json::from_value::<ImageFrame>(json).unwrap(), frame);
        assert!(MediaType::Png.matches(&frame.data));
        assert!(!MediaType::Jpeg.matches(&frame.data));
        assert_eq!(MediaType::from_format("jpg"), Some(MediaType::Jpeg));
        assert_eq!(MediaType::from_format("gif"), None);
    }
}
