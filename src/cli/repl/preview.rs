//! The live preview: takes the renderer's current frame (and, with `:mesh`, its placed
//! meshes), writes it to the preview PNG and shows it — inline in terminals that speak the
//! kitty or iTerm2 image protocol or sixel, else as one line naming the file. Never prints escape
//! sequences unless interactive.

use lapclone::util::ShowPath;
use std::io::Write as _;
use std::path::PathBuf;

use anyhow::Context as _;
use lapclone::raster::overlay::{draw_mesh_overlay, OverlayStyle};
use lapclone::render::Renderer;

/// How the terminal can show images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Inline {
    Kitty,
    Iterm,
    Sixel,
    /// Text line only (also every non-interactive session).
    None,
}

impl Inline {
    /// Detects the image protocol from the environment. `LAPCLONE_INLINE` = `off`, `kitty`,
    /// `iterm` or `sixel` overrides the detection.
    pub fn detect(interactive: bool) -> Inline {
        let var = |name: &str| std::env::var(name).unwrap_or_default();
        if !interactive {
            return Inline::None;
        }
        match var("LAPCLONE_INLINE").as_str() {
            "off" => return Inline::None,
            "kitty" => return Inline::Kitty,
            "iterm" => return Inline::Iterm,
            "sixel" => return Inline::Sixel,
            _ => {}
        }
        if !var("KITTY_WINDOW_ID").is_empty() || var("TERM").contains("kitty") {
            return Inline::Kitty;
        }
        let program = var("TERM_PROGRAM");
        if program == "iTerm.app" || program == "WezTerm" || var("LC_TERMINAL") == "iTerm2" {
            return Inline::Iterm;
        }
        let term = var("TERM");
        if term.contains("sixel") || term.starts_with("foot") || term.starts_with("mlterm") {
            return Inline::Sixel;
        }
        Inline::None
    }
}

pub struct Preview {
    pub path: PathBuf,
    pub inline: Inline,
    pub overlay: bool,
    announced: bool,
    interactive: bool,
}

impl Preview {
    pub fn new(path: PathBuf, interactive: bool, inline: Inline) -> Self {
        Preview {
            path,
            inline,
            overlay: false,
            announced: false,
            interactive,
        }
    }

    /// Writes the renderer's current frame (with the overlay if on) and shows it.
    pub fn update(&mut self, renderer: &Renderer) -> anyhow::Result<()> {
        let png = self.encode(renderer)?;
        lapclone::util::write_atomic(&self.path, &png)
            .with_context(|| format!("writing the preview {}", self.path.shown()))?;
        self.show(renderer, &png);
        Ok(())
    }

    fn encode(&self, renderer: &Renderer) -> anyhow::Result<Vec<u8>> {
        let frame = renderer.frame();
        if !self.overlay {
            return Ok(frame.encode_png(renderer.output_format())?);
        }
        let mut picture = frame.to_rgba8_image();
        let style = OverlayStyle::default();
        for placed in renderer.placed_meshes() {
            if placed.placed.len() != placed.mesh.vertex_count() {
                continue;
            }
            picture = draw_mesh_overlay(
                &picture,
                placed.placed,
                &placed.mesh.triangles,
                &placed.mesh.loops,
                &[],
                &style,
            )
            .with_context(|| format!("mesh overlay of `{}`", placed.name))?;
        }
        Ok(lapclone::golden::encode_rgba_png(&picture))
    }

    fn show(&mut self, renderer: &Renderer, png: &[u8]) {
        let canvas = &renderer.scene().canvas;
        let stats = renderer.last_stats();
        let line = format!(
            "preview: {} ({}×{}, t = {} s, {:.1} ms{})",
            self.path.shown(),
            canvas.width,
            canvas.height,
            lapclone::util::number_text(stats.time),
            stats.total_ms,
            if self.overlay { ", mesh" } else { "" }
        );
        match self.inline {
            Inline::None if self.interactive => crate::cli::print_line(&line),
            Inline::None => {
                if !self.announced {
                    crate::cli::print_line(format_args!("preview: {}", self.path.shown()));
                }
            }
            protocol => {
                if protocol == Inline::Sixel {
                    print_sixel(renderer);
                } else {
                    print_inline(protocol, png);
                }
                crate::cli::print_line(format_args!("{}", line.replacen("preview: ", "", 1)));
            }
        }
        self.announced = true;
    }
}

/// Shows `picture` inline when stdout is a terminal that speaks an image protocol; returns
/// false, having printed nothing, otherwise.
pub fn show_picture(picture: &image::RgbaImage) -> bool {
    use std::io::IsTerminal as _;
    match Inline::detect(std::io::stdout().is_terminal()) {
        Inline::None => false,
        Inline::Sixel => write_sixel(picture),
        protocol => {
            print_inline(protocol, &lapclone::golden::encode_rgba_png(picture));
            true
        }
    }
}

/// The default preview file: one per process in the system temp folder.
/// The default preview: `preview.png` in a folder of its own under the system temp folder,
/// with a random name and readable by this user only, so nothing another process planted
/// there (a link, a FIFO) can be followed. The folder goes when the guard is dropped.
pub fn default_preview_path() -> anyhow::Result<(PathBuf, tempfile::TempDir)> {
    let folder = tempfile::Builder::new()
        .prefix("lapclone-preview-")
        .tempdir()
        .context("creating the preview's temporary folder")?;
    Ok((folder.path().join("preview.png"), folder))
}

fn print_inline(protocol: Inline, png: &[u8]) {
    let data = base64(png);
    let mut out = std::io::stdout().lock();
    let _ = match protocol {
        Inline::Kitty => write_kitty(&mut out, &data),
        Inline::Iterm => writeln!(
            out,
            "\x1b]1337;File=inline=1;size={};width=64;preserveAspectRatio=1:{data}\x07",
            png.len()
        ),
        Inline::None | Inline::Sixel => Ok(()),
    };
    let _ = out.flush();
}

fn print_sixel(renderer: &Renderer) {
    // A preview that cannot be encoded is skipped; the text line still names the PNG.
    write_sixel(&renderer.frame().to_rgba8_image());
}

/// Draws `picture` as sixel graphics; false (nothing printed) if it cannot be encoded.
fn write_sixel(picture: &image::RgbaImage) -> bool {
    let Ok(text) = super::sixel::encode_sixel(picture) else {
        return false;
    };
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{text}");
    let _ = out.flush();
    true
}

/// Kitty's graphics protocol: the PNG in base64 chunks of at most 4096 bytes.
fn write_kitty(out: &mut impl std::io::Write, data: &str) -> std::io::Result<()> {
    let chunks: Vec<&[u8]> = data.as_bytes().chunks(4096).collect();
    for (i, chunk) in chunks.iter().enumerate() {
        let more = u8::from(i + 1 < chunks.len());
        let chunk = std::str::from_utf8(chunk).unwrap_or_default();
        if i == 0 {
            write!(out, "\x1b_Ga=T,f=100,c=64,m={more};{chunk}\x1b\\")?;
        } else {
            write!(out, "\x1b_Gm={more};{chunk}\x1b\\")?;
        }
    }
    writeln!(out)
}

/// Standard base64 with padding (RFC 4648), as both protocols expect.
pub fn base64(bytes: &[u8]) -> String {
    use ::base64::Engine as _;
    ::base64::engine::general_purpose::STANDARD.encode(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648_vectors() {
        for (input, expected) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(input.as_bytes()), expected);
        }
    }

    #[test]
    fn kitty_chunks_are_at_most_4096_bytes_and_flag_continuation() {
        let data = "A".repeat(5000);
        let mut out = Vec::new();
        write_kitty(&mut out, &data).unwrap();
        let text = String::from_utf8(out).unwrap();
        assert!(text.starts_with("\x1b_Ga=T,f=100,c=64,m=1;"));
        assert!(text.contains("\x1b_Gm=0;"));
        assert_eq!(text.matches('A').count(), 5000);
    }

    #[test]
    fn non_interactive_never_uses_an_image_protocol() {
        assert_eq!(Inline::detect(false), Inline::None);
    }
}
