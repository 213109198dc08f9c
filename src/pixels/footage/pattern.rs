//! Footage file names: takes a printf-style pattern (`plate_%04d.png`, `%d`, `%0Nd`, `%%`)
//! and gives a [`Pattern`] that names frame n's file and finds the lowest number present.

use std::path::{Path, PathBuf};

use super::FootageError;

/// A printf-style file name: a prefix, one frame number (zero-padded to `digits`, 0 for
/// plain `%d`) and a suffix.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Pattern {
    folder: PathBuf,
    prefix: String,
    digits: usize,
    suffix: String,
    text: String,
}

impl Pattern {
    /// Parses `path`; `Ok(None)` when it holds no `%` at all (a plain file name).
    pub fn parse(path: &Path) -> Result<Option<Pattern>, FootageError> {
        let text = path.to_string_lossy().into_owned();
        if !text.contains('%') {
            return Ok(None);
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let folder = path.parent().map(Path::to_path_buf).unwrap_or_default();
        if folder.to_string_lossy().contains('%') {
            return Err(FootageError::NumberInFolder(text));
        }
        let (prefix, digits, suffix) = split_name(&name).map_err(|bad| match bad {
            PatternProblem::NoNumber => FootageError::NoNumber(text.clone()),
            PatternProblem::Bad => FootageError::BadPattern(text.clone()),
        })?;
        Ok(Some(Pattern {
            folder,
            prefix,
            digits,
            suffix,
            text,
        }))
    }

    /// The file of frame number `n`.
    pub fn path(&self, n: u64) -> PathBuf {
        let digits = self.digits;
        let name = format!("{}{n:0digits$}{}", self.prefix, self.suffix);
        self.folder.join(name)
    }

    /// The pattern as given.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// The number in `name` if it is one of this pattern's file names.
    pub fn number_of(&self, name: &str) -> Option<u64> {
        let middle = name
            .strip_prefix(&self.prefix)?
            .strip_suffix(&self.suffix)?;
        let all_digits = !middle.is_empty() && middle.bytes().all(|b| b.is_ascii_digit());
        let padded_ok = if self.digits == 0 {
            middle == "0" || !middle.starts_with('0')
        } else {
            middle.len() >= self.digits && (middle.len() == self.digits || !middle.starts_with('0'))
        };
        (all_digits && padded_ok).then(|| middle.parse().ok())?
    }

    /// The highest number any entry of the folder has under this pattern (a file or not),
    /// if one has.
    pub fn highest_number(&self) -> Option<u64> {
        self.numbers().ok()?.max()
    }

    /// The lowest frame number that has a file.
    pub fn lowest_number(&self) -> Result<u64, FootageError> {
        let no_files = || FootageError::NoFiles {
            pattern: self.text.clone(),
            folder: self.folder_or_here().to_path_buf(),
        };
        self.numbers().map_err(|_| no_files())?.min().ok_or_else(no_files)
    }

    /// The numbers of the folder's entries this pattern names.
    fn numbers(&self) -> std::io::Result<impl Iterator<Item = u64> + '_> {
        let entries = std::fs::read_dir(self.folder_or_here())?;
        Ok(entries
            .filter_map(|e| e.ok())
            .filter_map(|e| self.number_of(&e.file_name().to_string_lossy())))
    }

    /// The pattern's folder, `.` for a bare file name.
    fn folder_or_here(&self) -> &Path {
        if self.folder.as_os_str().is_empty() {
            Path::new(".")
        } else {
            &self.folder
        }
    }
}

enum PatternProblem {
    NoNumber,
    Bad,
}

/// Splits a file name around its one `%d` / `%0Nd`, unescaping `%%`.
fn split_name(name: &str) -> Result<(String, usize, String), PatternProblem> {
    let mut parts = (String::new(), String::new());
    let mut digits = None;
    let mut chars = name.chars().peekable();
    while let Some(c) = chars.next() {
        let part = if digits.is_some() {
            &mut parts.1
        } else {
            &mut parts.0
        };
        if c != '%' {
            part.push(c);
            continue;
        }
        if chars.peek() == Some(&'%') {
            chars.next();
            part.push('%');
            continue;
        }
        let mut width = String::new();
        while let Some(d) = chars.peek().filter(|d| d.is_ascii_digit()) {
            width.push(*d);
            chars.next();
        }
        let zero_padded = width.is_empty() || (width.starts_with('0') && width.len() >= 2);
        if chars.next() != Some('d') || !zero_padded || digits.is_some() {
            return Err(PatternProblem::Bad);
        }
        let n: usize = if width.is_empty() {
            0
        } else {
            width.parse().map_err(|_| PatternProblem::Bad)?
        };
        if n > 18 {
            return Err(PatternProblem::Bad);
        }
        digits = Some(n);
    }
    let digits = digits.ok_or(PatternProblem::NoNumber)?;
    Ok((parts.0, digits, parts.1))
}


#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_parse_and_format() {
        let p = Pattern::parse(Path::new("dir/plate_%04d.png"))
            .unwrap()
            .unwrap();
        assert_eq!(p.path(7), Path::new("dir/plate_0007.png"));
        assert_eq!(p.path(12345), Path::new("dir/plate_12345.png"));
        assert_eq!(p.number_of("plate_0042.png"), Some(42));
        assert_eq!(p.number_of("plate_042.png"), None);
        let q = Pattern::parse(Path::new("f%d_100%%.png")).unwrap().unwrap();
        assert_eq!(q.path(3), Path::new("f3_100%.png"));
        assert_eq!(q.number_of("f03_100%.png"), None);
        assert_eq!(q.number_of("f30_100%.png"), Some(30));
        assert!(Pattern::parse(Path::new("plain.png")).unwrap().is_none());
    }

    #[test]
    fn bad_patterns_are_refused() {
        for bad in ["a_%s.png", "a_%4d.png", "a_%d_%d.png", "a%"] {
            assert!(
                matches!(
                    Pattern::parse(Path::new(bad)),
                    Err(FootageError::BadPattern(_))
                ),
                "{bad}"
            );
        }
        assert!(matches!(
            Pattern::parse(Path::new("100%%.png")),
            Err(FootageError::NoNumber(_))
        ));
        assert!(matches!(
            Pattern::parse(Path::new("d%04d/a.png")),
            Err(FootageError::NumberInFolder(_))
        ));
    }
}
