//! PNG images of femu's SVG charts (the sensor-removal study, the error map), rasterised by resvg
//! with the DejaVu Sans font shipped in this crate's `assets/fonts` (so text renders the same on a machine
//! without fonts), for reports and viewers that do not show SVG.

use crate::StudyError;
use std::path::Path;
use std::sync::Arc;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");

/// Rasterises SVG text at `scale` (1 = the SVG's own pixel size) to PNG bytes.
///
/// # Errors
/// [`StudyError::Invalid`] for SVG resvg cannot read or an empty image.
pub fn svg_to_png(svg: &str, scale: f32) -> Result<Vec<u8>, StudyError> {
    let bad = |reason: String| StudyError::invalid("SVG to PNG", reason);
    if !(scale.is_finite() && scale > 0.0) {
        return Err(bad(format!("scale {scale} must be positive")));
    }
    let mut db = resvg::usvg::fontdb::Database::new();
    db.load_font_data(FONT.to_vec());
    db.set_sans_serif_family("DejaVu Sans");
    let options = resvg::usvg::Options {
        font_family: "DejaVu Sans".into(),
        fontdb: Arc::new(db),
        ..Default::default()
    };
    let tree = resvg::usvg::Tree::from_str(svg, &options)
        .map_err(|e| bad(format!("SVG not readable: {e}")))?;
    let size = tree
        .size()
        .to_int_size()
        .scale_by(scale)
        .ok_or_else(|| bad("empty image".into()))?;
    let mut pixmap = resvg::tiny_skia::Pixmap::new(size.width(), size.height())
        .ok_or_else(|| bad("empty image".into()))?;
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    pixmap
        .encode_png()
        .map_err(|e| bad(format!("PNG encoding failed: {e}")))
}

/// Writes [`svg_to_png`] of `svg` to `path`.
///
/// # Errors
/// As [`svg_to_png`], and [`StudyError::File`] naming the file.
pub fn write_png(svg: &str, scale: f32, path: impl AsRef<Path>) -> Result<(), StudyError> {
    let bytes = svg_to_png(svg, scale)?;
    std::fs::write(path.as_ref(), bytes).map_err(|e| StudyError::file(path.as_ref(), e))
}
