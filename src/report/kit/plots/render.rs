//! From the SVG that plotters draws to the files we write. plotters lays text out with
//! the embedded DejaVu Sans (its metrics), and usvg then turns every glyph of that font
//! into a path: the SVG needs no font on the reader's machine, and resvg rasterises the
//! same tree into an anti-aliased PNG. No system font is ever looked up.
//! In: a figure's SVG text. Out: PNG bytes, or SVG text with its glyphs as paths.

use resvg::usvg;
use std::sync::{Arc, OnceLock};

/// The family name the figures ask plotters for; it resolves to the embedded font.
pub const FAMILY: &str = "sans-serif";
/// Pixels per SVG unit in the PNG files.
pub const PNG_SCALE: u32 = 2;

/// Makes the embedded font the one plotters measures text with. Call before drawing.
pub fn register_font() {
    static REGISTERED: OnceLock<()> = OnceLock::new();
    REGISTERED.get_or_init(|| {
        plotters::style::register_font(
            FAMILY,
            plotters::style::FontStyle::Normal,
            dejavu::sans::regular(),
        )
        .unwrap_or_else(|_| panic!("the embedded DejaVu Sans is a valid font"));
    });
}

fn fonts() -> Arc<usvg::fontdb::Database> {
    static FONTS: OnceLock<Arc<usvg::fontdb::Database>> = OnceLock::new();
    FONTS
        .get_or_init(|| {
            let mut fonts = usvg::fontdb::Database::new();
            fonts.load_font_data(dejavu::sans::regular().to_vec());
            fonts.set_sans_serif_family("DejaVu Sans");
            Arc::new(fonts)
        })
        .clone()
}

/// Why a drawn figure could not be written as a file.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("rendering a figure: reading the SVG plotters drew")]
    Parse(#[source] usvg::Error),
    #[error("rendering a figure: its size {width} × {height} is empty")]
    Empty { width: u32, height: u32 },
    #[error("rendering a figure: encoding the PNG")]
    Encode(#[source] Box<dyn std::error::Error + Send + Sync>),
}

fn tree(svg: &str) -> Result<usvg::Tree, RenderError> {
    let options = usvg::Options {
        fontdb: fonts(),
        font_family: "DejaVu Sans".into(),
        ..Default::default()
    };
    usvg::Tree::from_str(svg, &options).map_err(RenderError::Parse)
}

/// The SVG with its text as paths.
pub fn svg_with_outlined_text(svg: &str) -> Result<String, RenderError> {
    Ok(tree(svg)?.to_string(&usvg::WriteOptions::default()))
}

/// The SVG rasterised at [`PNG_SCALE`] pixels per unit, PNG-encoded.
pub fn png(svg: &str) -> Result<Vec<u8>, RenderError> {
    let tree = tree(svg)?;
    let size = tree.size().to_int_size();
    let mut pixmap =
        resvg::tiny_skia::Pixmap::new(size.width() * PNG_SCALE, size.height() * PNG_SCALE).ok_or(
            RenderError::Empty {
                width: size.width(),
                height: size.height(),
            },
        )?;
    pixmap.fill(resvg::tiny_skia::Color::WHITE);
    let scale = PNG_SCALE as f32;
    resvg::render(
        &tree,
        resvg::tiny_skia::Transform::from_scale(scale, scale),
        &mut pixmap.as_mut(),
    );
    // tiny-skia's PNG error is of a png crate this crate does not name: boxed.
    pixmap
        .encode_png()
        .map_err(|e| RenderError::Encode(Box::new(e)))
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"<svg xmlns="http://www.w3.org/2000/svg" width="200" height="50" viewBox="0 0 200 50"><text x="10" y="30" font-family="sans-serif" font-size="20">RMSE ± σ</text></svg>"#;

    #[test]
    fn a_broken_svg_names_its_cause_once() {
        let error = png("<svg").unwrap_err();
        let cause = std::error::Error::source(&error)
            .expect("the parser's error is kept")
            .to_string();
        let chain = format!("{:#}", anyhow::Error::new(error));
        assert!(
            chain.starts_with("rendering a figure: reading the SVG plotters drew: "),
            "{chain}"
        );
        assert_eq!(chain.matches(&cause).count(), 1, "{chain}");
    }

    #[test]
    fn text_becomes_paths_drawn_with_the_embedded_font() {
        let svg = svg_with_outlined_text(TEXT).unwrap();
        assert!(!svg.contains("<text"), "{svg}");
        assert!(svg.contains("<path"), "{svg}");
        let png = png(TEXT).unwrap();
        let decoder = png::Decoder::new(std::io::Cursor::new(png));
        let mut reader = decoder.read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        assert_eq!((info.width, info.height), (400, 100));
        let dark = pixels.chunks(4).filter(|p| p[0] < 128).count();
        assert!(
            dark > 200,
            "only {dark} dark pixels: the text was not drawn"
        );
    }
}
