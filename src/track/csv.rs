//! Track CSV: takes tracked frames and gives the text `lapclone track` writes (a header,
//! then `frame,x,y,confidence` per frame for one point; `frame,point,x,y,confidence,rotate,
//! scale` per point per frame for two or more); and takes CSV text whose header names its
//! columns — `frame` (numbered as `render` numbers frames) or `t` (seconds), `x`, `y`, and
//! optionally `point`, `confidence`, `rotate`, `scale` — and gives each point's rows, or the
//! line and what is wrong with it.

use std::io::Write;

use glam::DVec2;

use super::{Estimate, TrackRow, TrackTime, MAX_POINTS, MAX_ROWS};

/// One tracked frame: its number (as `render` numbers frames), each point's estimate, and
/// with two or more points the pair's rotation (degrees) and scale against the first frame.
#[derive(Clone, Debug, PartialEq)]
pub struct TrackedFrame {
    /// The frame number, from 1.
    pub frame: u64,
    /// One estimate per point.
    pub points: Vec<Estimate>,
    /// Rotation and scale of points 1 → 2 relative to the first frame.
    pub pair: Option<(f64, f64)>,
}

/// Writes `frames` as track CSV.
pub fn write_csv(out: &mut impl Write, frames: &[TrackedFrame]) -> std::io::Result<()> {
    let several = frames.first().is_some_and(|f| f.points.len() > 1);
    if several {
        writeln!(out, "frame,point,x,y,confidence,rotate,scale")?;
    } else {
        writeln!(out, "frame,x,y,confidence")?;
    }
    for frame in frames {
        for (i, e) in frame.points.iter().enumerate() {
            let (x, y, c) = (e.at.x, e.at.y, e.confidence);
            if several {
                let (r, s) = frame.pair.unwrap_or((0.0, 1.0));
                let n = frame.frame;
                writeln!(out, "{n},{},{x:.4},{y:.4},{c:.3},{r:.4},{s:.6}", i + 1)?;
            } else {
                writeln!(out, "{},{x:.4},{y:.4},{c:.3}", frame.frame)?;
            }
        }
    }
    Ok(())
}

/// A column a track CSV may have.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Column {
    Frame,
    Seconds,
    Point,
    X,
    Y,
    Confidence,
    Rotate,
    Scale,
}

const COLUMNS: [(&str, Column); 8] = [
    ("frame", Column::Frame),
    ("t", Column::Seconds),
    ("point", Column::Point),
    ("x", Column::X),
    ("y", Column::Y),
    ("confidence", Column::Confidence),
    ("rotate", Column::Rotate),
    ("scale", Column::Scale),
];

type Failure = (usize, String);

/// Each point's rows from CSV `text`, its lines as [`numbered_lines`](super::numbered_lines)
/// gives them.
pub(super) fn parse(text: &str) -> Result<Vec<Vec<TrackRow>>, Failure> {
    let mut lines = super::numbered_lines(text)
        .map(|(number, l)| (number, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((header_line, header)) = lines.next() else {
        return Err((1, "the file is empty: expected a header such as frame,x,y".into()));
    };
    let columns = parse_header(header_line, header)?;
    let mut points: Vec<Vec<TrackRow>> = Vec::new();
    let mut count = 0usize;
    let mut last_line = header_line;
    for (number, line) in lines {
        last_line = number;
        count += 1;
        if count > MAX_ROWS {
            return Err((number, format!("more than {MAX_ROWS} rows")));
        }
        let (point, row) = parse_row(number, line, &columns)?;
        if points.len() < point {
            points.resize_with(point, Vec::new);
        }
        let rows = &mut points[point - 1];
        if let Some(previous) = rows.last() {
            check_order(number, point, previous.time, row.time)?;
        }
        rows.push(row);
    }
    if count == 0 {
        return Err((last_line + 1, "the file has a header but no rows".into()));
    }
    if let Some(missing) = points.iter().position(Vec::is_empty) {
        return Err((header_line, format!("point {} has no rows", missing + 1)));
    }
    Ok(points)
}

fn parse_header(line: usize, header: &str) -> Result<Vec<Column>, Failure> {
    // Past as many names as there are columns one must be unknown or repeated, which the
    // loop says; the rest of the line stays one slice instead of a list.
    let names: Vec<&str> = header.splitn(COLUMNS.len() + 1, ',').map(str::trim).collect();
    if names.iter().any(|n| n.parse::<f64>().is_ok()) {
        return Err((
            line,
            "missing header: the first line must name the columns, e.g. frame,x,y or t,x,y".into(),
        ));
    }
    let mut columns = Vec::with_capacity(names.len());
    for name in &names {
        let column = COLUMNS
            .iter()
            .find(|(n, _)| n.eq_ignore_ascii_case(name))
            .map(|(_, c)| *c)
            .ok_or_else(|| {
                let known: Vec<&str> = COLUMNS.iter().map(|(n, _)| *n).collect();
                let name = super::shown(name);
                (line, format!("unknown column `{name}` (known: {})", known.join(", ")))
            })?;
        if columns.contains(&column) {
            return Err((line, format!("column `{name}` appears twice")));
        }
        columns.push(column);
    }
    let has = |c| columns.contains(&c);
    if has(Column::Frame) == has(Column::Seconds) {
        return Err((line, "the header needs one time column: `frame` or `t` (seconds)".into()));
    }
    if !has(Column::X) || !has(Column::Y) {
        return Err((line, "the header needs `x` and `y` columns".into()));
    }
    Ok(columns)
}

fn parse_row(line: usize, text: &str, columns: &[Column]) -> Result<(usize, TrackRow), Failure> {
    // Counted before any list is made, so a huge line costs no memory.
    let found = text.bytes().filter(|&b| b == b',').count() + 1;
    if found != columns.len() {
        return Err((line, format!("expected {} values, found {found}", columns.len())));
    }
    let cells: Vec<&str> = text.split(',').map(str::trim).collect();
    let mut row = TrackRow {
        time: TrackTime::Seconds(0.0),
        at: DVec2::ZERO,
        confidence: None,
        rotate: None,
        scale: None,
    };
    let mut point = 1;
    for (cell, column) in cells.iter().zip(columns) {
        let name = COLUMNS.iter().find(|(_, c)| c == column).map_or("", |(n, _)| n);
        let value: f64 = cell
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| (line, format!("column `{name}`: `{}` is not a number", super::shown(cell))))?;
        match column {
            Column::Frame => row.time = TrackTime::Frame(whole(line, name, value, u64::MAX)?),
            Column::Seconds if value < 0.0 => {
                return Err((line, format!("column `t`: {value} is negative")))
            }
            Column::Seconds => row.time = TrackTime::Seconds(value),
            Column::Point => point = whole(line, name, value, MAX_POINTS as u64)? as usize,
            Column::X | Column::Y => match crate::limits::position_error(value) {
                Some(error) => return Err((line, format!("column `{name}`: {error}"))),
                None if *column == Column::X => row.at.x = value,
                None => row.at.y = value,
            },
            Column::Confidence => row.confidence = Some(value),
            Column::Rotate => match crate::limits::rotation_or_depth_error(value) {
                Some(error) => return Err((line, format!("column `rotate`: {error}"))),
                None => row.rotate = Some(value),
            },
            Column::Scale => match crate::limits::scale_error(value) {
                Some(error) => return Err((line, format!("column `scale`: {error}"))),
                None => row.scale = Some(value),
            },
        }
    }
    Ok((point, row))
}

/// A whole number from 1 to `max`.
fn whole(line: usize, name: &str, value: f64, max: u64) -> Result<u64, Failure> {
    if value.fract() != 0.0 || value < 1.0 || value > max as f64 {
        return Err((
            line,
            format!("column `{name}`: {value} must be a whole number from 1 to {max}"),
        ));
    }
    Ok(value as u64)
}

fn check_order(line: usize, point: usize, before: TrackTime, now: TrackTime) -> Result<(), Failure> {
    let (a, b, what) = match (before, now) {
        (TrackTime::Frame(a), TrackTime::Frame(b)) => (a as f64, b as f64, "frame"),
        (TrackTime::Seconds(a), TrackTime::Seconds(b)) => (a, b, "t"),
        // invariant: one header gives every row the same kind of time.
        _ => unreachable!("one time column per file"),
    };
    if b <= a {
        return Err((
            line,
            format!("{what} {b} comes after {what} {a} (point {point}): times must increase"),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spreadsheet_csv_reads_and_errors_quote_little() {
        let plain = parse("frame,x,y\n1,2,3\n2,4,5\n").unwrap();
        // Line ends mixed in one file too: lone-CR lines ending in a CRLF.
        let mixed = "frame,x,y\r1,2,3\r2,4,5\r\n";
        for text in ["\u{feff}frame,x,y\r\n1,2,3\r\n2,4,5\r\n", "frame,x,y\r1,2,3\r2,4,5\r", mixed] {
            assert_eq!(parse(text).unwrap(), plain, "{text:?}");
        }
        let (line, message) = parse("frame,x,y\r\n1,2,3\r\n2,4,5\u{1b}z\r\n").unwrap_err();
        assert_eq!(line, 3);
        assert!(message.contains("`5\\u{1b}z`"), "{message}");
        let long = format!("frame,x,y\n1,2,{}\n", "7".repeat(100_000));
        let (_, message) = parse(&long).unwrap_err();
        assert!(message.len() < 200 && message.contains("(100000 characters)"), "{message}");
    }

    #[test]
    fn written_csv_reads_back() {
        let e = |x, y, c| Estimate {
            at: DVec2::new(x, y),
            confidence: c,
            lost: None,
        };
        let frames = vec![
            TrackedFrame {
                frame: 3,
                points: vec![e(1.5, 2.25, 1.0), e(11.5, 2.25, 1.0)],
                pair: Some((0.0, 1.0)),
            },
            TrackedFrame {
                frame: 4,
                points: vec![e(1.75, 2.5, 0.9), e(11.75, 3.5, 0.95)],
                pair: Some((5.7106, 1.004988)),
            },
        ];
        let mut text = Vec::new();
        write_csv(&mut text, &frames).unwrap();
        let points = parse(std::str::from_utf8(&text).unwrap()).unwrap();
        assert_eq!(points.len(), 2);
        assert_eq!(points[1][1].at, DVec2::new(11.75, 3.5));
        assert_eq!(points[0][1].time, TrackTime::Frame(4));
        assert_eq!(points[0][1].rotate, Some(5.7106));
        assert_eq!(points[0][1].confidence, Some(0.9));
    }

    #[test]
    fn problems_are_placed_on_their_line() {
        let err = |text: &str| parse(text).unwrap_err();
        assert_eq!(err("\n1,2,3\n").0, 2);
        assert!(err("frame,x,y\n1,2,zz\n").1.contains("`zz` is not a number"));
        assert_eq!(err("frame,x,y\n2,0,0\n\n1,0,0\n").0, 4);
        assert_eq!(err("frame,x,y\n").0, 2);
        assert!(err("frame,x\n").1.contains("`x` and `y`"));
        // Finite but out of reach: the row is named, not the patch at render time.
        let far = err("frame,x,y\n1,2,3\n2,-1e308,3\n");
        assert_eq!(far, (3, "column `x`: -1e308 is past ±1e9 px".into()));
        let huge = err("frame,x,y,scale\n1,2,3,1e308\n");
        assert_eq!(huge, (2, "column `scale`: 1e308 must be > 0 and at most 1e6".into()));
        assert!(err("frame,x,y,scale\n1,2,3,0\n").1.contains("0 must be > 0"));
        assert!(parse("frame,x,y,scale\n1,1e9,-1e9,1e6\n").is_ok(), "the bounds themselves");
        // A rotation is bounded as a keyed one is: ±1e308 eased to ±inf.
        let turned = err("t,x,y,rotate\n0,40,30,1.7e308\n");
        assert_eq!(turned, (2, "column `rotate`: 1.7e308 is past ±1e9".into()));
        assert!(parse("frame,x,y,rotate\n1,1,1,-1e9\n").is_ok());
    }
}
