//! After Effects' "Adobe After Effects 8.0 Keyframe Data" clipboard text: takes the text
//! and gives one point's rows — Transform Position keys, with Rotation (degrees) and Scale
//! (percent → factor, the mean of X and Y) sampled at each position key (linear between
//! their own keys, held beyond them) — at frame / Units Per Second seconds. Sections other
//! than these three are skipped; a malformed line is reported with its number.

use glam::DVec2;

use super::{TrackRow, TrackTime, MAX_ROWS};

type Failure = (usize, String);

/// Whether `text` is keyframe data (its first non-blank line says so).
pub(super) fn is_keyframe_data(text: &str) -> bool {
    super::numbered_lines(text)
        .map(|(_, line)| line.trim())
        .find(|l| !l.is_empty())
        .is_some_and(|l| l.starts_with("Adobe After Effects") && l.ends_with("Keyframe Data"))
}

#[derive(Clone, Copy, PartialEq)]
enum Section {
    Header,
    Position,
    Rotation,
    Scale,
    Other,
}

#[derive(Default)]
struct Keys {
    units_per_second: Option<f64>,
    position: Vec<(f64, DVec2, usize)>,
    rotation: Vec<(f64, f64)>,
    scale: Vec<(f64, f64)>,
}

/// Most values one line holds: a key has a frame and up to three, other sections' lines a
/// few more; the bound keeps one huge line from becoming a huge list.
const MAX_CELLS: usize = 64;

/// The rows of the one point keyframe data holds.
pub(super) fn parse(text: &str) -> Result<Vec<Vec<TrackRow>>, Failure> {
    let mut keys = Keys::default();
    let mut section = Section::Header;
    let mut last_line = 1;
    let lines = super::numbered_lines(text).skip_while(|(_, l)| l.trim().is_empty());
    for (number, line) in lines.skip(1) {
        last_line = number;
        let cells: Vec<&str> = line
            .split('\t')
            .map(str::trim)
            .filter(|c| !c.is_empty())
            .take(MAX_CELLS + 1)
            .collect();
        if cells.len() > MAX_CELLS {
            return Err((number, format!("more than {MAX_CELLS} values on one line")));
        }
        match cells.as_slice() {
            [] => continue,
            ["End of Keyframe Data"] => break,
            // Section titles start at the line's beginning; keys are indented.
            [first, rest @ ..] if !line.starts_with(char::is_whitespace) => {
                section = match rest {
                    [name] if *first == "Transform" => section_named(name),
                    _ => Section::Other,
                }
            }
            [first, ..] if first.parse::<f64>().is_err() => {
                if section == Section::Header {
                    header_line(&mut keys, number, &cells)?;
                } else if *first != "Frame" && section != Section::Other {
                    return Err((number, format!("`{}` is not a frame number", super::shown(first))));
                }
            }
            _ => key_line(&mut keys, section, number, &cells)?,
        }
        if keys.position.len() + keys.rotation.len() + keys.scale.len() > MAX_ROWS {
            return Err((number, format!("more than {MAX_ROWS} keys")));
        }
    }
    rows(&keys, last_line)
}

fn section_named(name: &str) -> Section {
    match name {
        "Position" => Section::Position,
        "Rotation" => Section::Rotation,
        "Scale" => Section::Scale,
        _ => Section::Other,
    }
}

/// A `Units Per Second`, `Source Width`… line before the first section.
fn header_line(keys: &mut Keys, number: usize, cells: &[&str]) -> Result<(), Failure> {
    if let ["Units Per Second", value] = cells {
        let ups = value
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite() && *v > 0.0)
            .ok_or_else(|| (number, format!("Units Per Second `{value}` is not a positive number")))?;
        keys.units_per_second = Some(ups);
    }
    Ok(())
}

fn key_line(keys: &mut Keys, section: Section, number: usize, cells: &[&str]) -> Result<(), Failure> {
    let values = cells
        .iter()
        .map(|c| {
            c.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| (number, format!("`{}` is not a number", super::shown(c))))
        })
        .collect::<Result<Vec<f64>, Failure>>()?;
    let need = match section {
        Section::Position => 3,
        Section::Rotation => 2,
        Section::Scale => 2,
        Section::Header => return Err((number, "a key before any `Transform` section".into())),
        Section::Other => return Ok(()),
    };
    if values.len() < need {
        return Err((number, format!("expected a frame and {} values", need - 1)));
    }
    let frame = values[0];
    if frame < 0.0 {
        return Err((number, format!("frame {frame} is negative")));
    }
    let previous = match section {
        Section::Position => keys.position.last().map(|k| k.0),
        Section::Rotation => keys.rotation.last().map(|k| k.0),
        _ => keys.scale.last().map(|k| k.0),
    };
    if previous.is_some_and(|p| frame <= p) {
        return Err((
            number,
            format!("frame {frame} comes after frame {}: frames must increase", previous.unwrap_or(0.0)),
        ));
    }
    match section {
        Section::Position => {
            if let Some(error) = values[1..3].iter().find_map(|&v| crate::limits::position_error(v)) {
                return Err((number, format!("position {error}")));
            }
            keys.position.push((frame, DVec2::new(values[1], values[2]), number))
        }
        Section::Rotation => {
            if let Some(error) = crate::limits::rotation_or_depth_error(values[1]) {
                return Err((number, format!("rotation {error}")));
            }
            keys.rotation.push((frame, values[1]))
        }
        _ => {
            let y = values.get(2).copied().unwrap_or(values[1]);
            let factor = (values[1] + y) / 200.0;
            if let Some(error) = crate::limits::scale_error(factor) {
                return Err((number, format!("scale {error}")));
            }
            keys.scale.push((frame, factor));
        }
    }
    Ok(())
}

fn rows(keys: &Keys, last_line: usize) -> Result<Vec<Vec<TrackRow>>, Failure> {
    let Some(ups) = keys.units_per_second else {
        return Err((last_line, "no `Units Per Second` line before the keys".into()));
    };
    if keys.position.is_empty() {
        return Err((last_line, "no `Transform Position` keys".into()));
    }
    let rows = keys
        .position
        .iter()
        .map(|&(frame, at, _)| TrackRow {
            time: TrackTime::Seconds(frame / ups),
            at,
            confidence: None,
            rotate: sample(&keys.rotation, frame),
            scale: sample(&keys.scale, frame),
        })
        .collect();
    Ok(vec![rows])
}

/// The value of `keys` at `frame`: linear between keys, held beyond them.
fn sample(keys: &[(f64, f64)], frame: f64) -> Option<f64> {
    let first = keys.first()?;
    let last = keys.last()?;
    if frame <= first.0 {
        return Some(first.1);
    }
    if frame >= last.0 {
        return Some(last.1);
    }
    let end = keys.partition_point(|k| k.0 <= frame);
    let (a, b) = (keys[end - 1], keys[end]);
    Some(a.1 + (b.1 - a.1) * (frame - a.0) / (b.0 - a.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    const SAMPLE: &str = "Adobe After Effects 8.0 Keyframe Data\n\n\tUnits Per Second\t24\n\tSource Width\t320\n\tSource Height\t240\n\tSource Pixel Aspect Ratio\t1\n\tComp Pixel Aspect Ratio\t1\n\nTransform\tPosition\n\tFrame\tX pixels\tY pixels\tZ pixels\t\n\t0\t100.5\t80.25\t0\t\n\t1\t101.5\t81.25\t0\t\n\nTransform\tRotation\n\tFrame\tdegrees\t\n\t0\t0\t\n\t1\t2\t\n\nTransform\tScale\n\tFrame\tX percent\tY percent\tZ percent\t\n\t0\t100\t100\t100\t\n\nEnd of Keyframe Data\n";

    #[test]
    fn reads_position_rotation_and_scale() {
        assert!(is_keyframe_data(SAMPLE));
        let points = parse(SAMPLE).unwrap();
        let rows = &points[0];
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[1].time, TrackTime::Seconds(1.0 / 24.0));
        assert_eq!(rows[1].at, DVec2::new(101.5, 81.25));
        assert_eq!(rows[1].rotate, Some(2.0));
        assert_eq!(rows[1].scale, Some(1.0));
    }

    /// Keyframe text saved with a byte-order mark, Windows or old-Mac line ends reads as
    /// the plain text does (it was taken for CSV), and errors keep their line numbers.
    #[test]
    fn a_byte_order_mark_and_any_line_ends_read_the_same() {
        let want = parse(SAMPLE).unwrap();
        let bad = SAMPLE.replace("\t101.5\t", "\tabc\t");
        for (bom, ending) in [("\u{feff}", "\n"), ("", "\r\n"), ("\u{feff}", "\r")] {
            let text = format!("{bom}{}", SAMPLE.replace('\n', ending));
            assert!(is_keyframe_data(&text), "{ending:?}");
            assert_eq!(parse(&text).unwrap(), want, "{ending:?}");
            let bad = format!("{bom}{}", bad.replace('\n', ending));
            assert_eq!(parse(&bad).unwrap_err().0, 12, "{ending:?}");
        }
    }

    #[test]
    fn a_bad_number_names_its_line() {
        let bad = SAMPLE.replace("\t101.5\t", "\tabc\t");
        let (line, message) = parse(&bad).unwrap_err();
        assert_eq!(line, 12);
        assert!(message.contains("`abc`"), "{message}");
    }

    #[test]
    fn a_far_position_or_a_huge_scale_names_its_line() {
        let far = SAMPLE.replace("\t101.5\t", "\t1e308\t");
        assert_eq!(parse(&far).unwrap_err(), (12, "position 1e308 is past ±1e9 px".into()));
        let turned = SAMPLE.replace("\t1\t2\t\n", "\t1\t-1.7e308\t\n");
        assert!(parse(&turned).unwrap_err().1.contains("rotation -1.7e308 is past ±1e9"));
        let huge = SAMPLE.replace("\t0\t100\t100\t100\t", "\t0\t1e308\t1e308\t100\t");
        let (line, message) = parse(&huge).unwrap_err();
        assert_eq!(line, 21);
        assert!(message.contains("scale inf must be > 0 and at most 1e6"), "{message}");
    }
}
