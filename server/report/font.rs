//! The one font every figure uses, compiled into the binary.
//!
//! plotters' `ab_glyph` feature lays out and rasterises text with a font we hand it instead of
//! asking the system (its default `ttf` feature needs fontconfig and freetype, and PNGs come out
//! without text on machines that have no fonts installed). DejaVu Sans 2.37 is shipped in
//! `assets/fonts/` with its licence (Bitstream Vera terms, DejaVu changes public domain).

use std::sync::Once;

use plotters::style::FontStyle;

static DEJAVU_SANS: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// The family name the figures ask for; plotters maps `FontFamily::SansSerif` to it.
pub const FAMILY: &str = "sans-serif";

/// Registers DejaVu Sans as `sans-serif` (every style falls back to it). Idempotent and cheap
/// after the first call, so every drawing function calls it first.
pub fn ensure_registered() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        // The bytes are our own asset, checked by a test: a failure here is a broken build.
        if plotters::style::register_font(FAMILY, FontStyle::Normal, DEJAVU_SANS).is_err() {
            panic!("assets/fonts/DejaVuSans.ttf is not a valid font");
        }
    });
}

#[cfg(test)]
mod tests {
    #[test]
    fn report_embedded_font_registers() {
        super::ensure_registered();
        super::ensure_registered();
    }
}
