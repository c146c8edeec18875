//! Bounded line reading: one line at a time from any [`BufRead`], never more than
//! [`MAX_LINE_BYTES`] of it in memory, numbered from 1.

use std::borrow::Cow;
use std::io::{BufRead, Read};

use super::ParseError;

/// The longest line a reader takes (a point's line is well under 1 KB; a file without
/// line ends is refused here instead of being read whole).
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Lines of a reader.
pub(super) struct Lines<R> {
    reader: R,
    buf: Vec<u8>,
    number: usize,
}

impl<R: BufRead> Lines<R> {
    /// Lines of `reader` from where it stands.
    pub fn new(reader: R) -> Self {
        Lines { reader, buf: Vec::new(), number: 0 }
    }

    /// The next line's number and text (without `\n` or `\r\n`; invalid UTF-8 replaced),
    /// or `None` at the end.
    pub fn next_line(&mut self) -> Result<Option<(usize, Cow<'_, str>)>, ParseError> {
        Ok(self.advance()?.then(|| (self.number, String::from_utf8_lossy(&self.buf))))
    }

    /// The next line that is not blank (only whitespace), or `None` at the end.
    pub fn next_nonblank(&mut self) -> Result<Option<(usize, Cow<'_, str>)>, ParseError> {
        loop {
            if !self.advance()? {
                return Ok(None);
            }
            if !String::from_utf8_lossy(&self.buf).trim().is_empty() {
                return Ok(Some((self.number, String::from_utf8_lossy(&self.buf))));
            }
        }
    }

    /// Read the next line into `buf`: false at the end.
    fn advance(&mut self) -> Result<bool, ParseError> {
        self.buf.clear();
        let n =
            (&mut self.reader).take(MAX_LINE_BYTES as u64 + 1).read_until(b'\n', &mut self.buf).map_err(read_error)?;
        if n == 0 {
            return Ok(false);
        }
        self.number += 1;
        if self.buf.last() == Some(&b'\n') {
            self.buf.pop();
            if self.buf.last() == Some(&b'\r') {
                self.buf.pop();
            }
        } else if self.buf.len() > MAX_LINE_BYTES {
            return Err(ParseError::LineTooLong { line: self.number, limit: MAX_LINE_BYTES });
        }
        Ok(true)
    }

    /// Lines read so far.
    pub fn count(&self) -> usize {
        self.number
    }

    /// The reader, just after the last line read.
    pub fn into_inner(self) -> R {
        self.reader
    }
}

/// A read error in the middle of a file.
pub(super) fn read_error(e: std::io::Error) -> ParseError {
    ParseError::Read(e.to_string())
}

/// Refuse a point beyond `limit` (checked before it is stored).
pub(super) fn check_limit(points: usize, limit: usize) -> Result<(), ParseError> {
    if points >= limit {
        return Err(ParseError::TooManyPoints { limit });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_are_numbered_and_trimmed_of_their_ends() {
        let mut l = Lines::new(&b"a\r\nb\n\nc"[..]);
        let mut got = Vec::new();
        while let Some((n, t)) = l.next_line().unwrap() {
            got.push((n, t.into_owned()));
        }
        assert_eq!(got, [(1, "a".into()), (2, "b".into()), (3, String::new()), (4, "c".into())]);
    }

    #[test]
    fn a_line_over_the_limit_is_an_error_without_reading_it_whole() {
        let mut text = b"1 2 3\n".to_vec();
        text.extend(std::iter::repeat_n(b'7', MAX_LINE_BYTES + 10));
        let mut l = Lines::new(&text[..]);
        assert!(l.next_line().unwrap().is_some());
        let e = l.next_line().unwrap_err();
        assert_eq!(e, ParseError::LineTooLong { line: 2, limit: MAX_LINE_BYTES });
        // A line of exactly the limit is fine.
        let mut exact = vec![b'7'; MAX_LINE_BYTES];
        exact.push(b'\n');
        assert_eq!(Lines::new(&exact[..]).next_line().unwrap().unwrap().1.len(), MAX_LINE_BYTES);
    }
}
