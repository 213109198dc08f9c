//! The output format a path or a name gives, and the Y4M header's frame-rate fractions.

use lapclone::output::{fps_fraction, OutputError, OutputKind};
use std::path::Path;

#[test]
fn extensions_name_their_formats() {
    let kind = |p: &str| OutputKind::from_path(Path::new(p));
    assert_eq!(kind("out/cat.gif"), Ok(OutputKind::Gif));
    assert_eq!(kind("cat.MP4"), Ok(OutputKind::Mp4));
    assert_eq!(kind("cat.png"), Ok(OutputKind::PngFolder));
    assert_eq!(kind("cat.apng"), Ok(OutputKind::Apng));
    assert_eq!(kind("frames"), Ok(OutputKind::PngFolder));
    assert_eq!(kind("-"), Ok(OutputKind::Y4m));
    assert_eq!(kind("cat.jpg"), Err("jpg".to_string()));
}

#[test]
fn names_and_paths_resolve_to_formats() {
    assert_eq!(OutputKind::from_name("GIF").ok(), Some(OutputKind::Gif));
    assert_eq!(
        OutputKind::from_name("png").ok(),
        Some(OutputKind::PngFolder)
    );
    assert!(matches!(
        OutputKind::from_name("jpeg"),
        Err(OutputError::UnknownFormat(name)) if name == "jpeg"
    ));
    let resolve = |p: &str, f| OutputKind::resolve(Path::new(p), f);
    assert_eq!(
        resolve("a.mp4", Some(OutputKind::Y4m)).ok(),
        Some(OutputKind::Y4m)
    );
    assert_eq!(resolve("a.apng", None).ok(), Some(OutputKind::Apng));
    assert!(matches!(
        resolve("a.bmp", None),
        Err(OutputError::UnknownExtension { .. })
    ));
    assert!(matches!(
        resolve("-", Some(OutputKind::Gif)),
        Err(OutputError::StdoutNeedsY4m)
    ));
}

#[test]
fn rates_become_fractions() {
    assert_eq!(fps_fraction(24.0), (24, 1));
    assert_eq!(fps_fraction(30000.0 / 1001.0), (30000, 1001));
    assert_eq!(fps_fraction(12.5), (25, 2));
    // A third exactly (a thousandth made 9 s of frames last 9.009 s); the slowest and a
    // rate typed to the thousandth as typed.
    assert_eq!(fps_fraction(1.0 / 3.0), (1, 3));
    assert_eq!(fps_fraction(0.01), (1, 100));
    assert_eq!(fps_fraction(23.976), (2997, 125));
    // Any other rate at least as near as its thousandths (denominators up to 1000), and
    // exactly when it has three decimals.
    for k in 1..2000 {
        let fps = 0.01 + k as f64 * 0.4999;
        let (num, den) = fps_fraction(fps);
        let error = (num as f64 / den as f64 - fps).abs();
        assert!(den <= 1001 && error <= 0.5e-3 + 1e-12, "{fps}: {num}/{den}");
        let typed = (fps * 1000.0).round() / 1000.0;
        let (num, den) = fps_fraction(typed);
        assert!(
            (num as f64 / den as f64 - typed).abs() < 1e-9,
            "{typed}: {num}/{den}"
        );
    }
}
