//! The word stream of the NFF family (NFF, BART's AFF). Both formats are free-form: BART's
//! reference parser reads them with `fscanf`, so a command may span lines (`xs` puts its scale,
//! rotation and translation on three), and `#` or `%` starts a comment that runs to the end of
//! the line. Every word keeps its line number so that an error can name it.

use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};

pub struct Tokens<'a> {
    path: &'a Path,
    words: Vec<(&'a str, usize)>,
    next: usize,
}

impl<'a> Tokens<'a> {
    pub fn new(path: &'a Path, text: &'a str) -> Self {
        // A byte-order mark (editors on Windows write one) is not part of the first word.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut words = Vec::new();
        for (index, line) in text.lines().enumerate() {
            let content = line.split(['#', '%']).next().unwrap_or("");
            words.extend(content.split_whitespace().map(|w| (w, index + 1)));
        }
        Tokens {
            path,
            words,
            next: 0,
        }
    }

    pub fn path(&self) -> &'a Path {
        self.path
    }

    pub fn peek(&self) -> Option<&'a str> {
        self.words.get(self.next).map(|&(w, _)| w)
    }

    pub fn remaining(&self) -> usize {
        self.words.len() - self.next
    }

    /// Line of the word read last (of the first word before anything is read).
    pub fn line(&self) -> usize {
        let index = self.next.saturating_sub(1);
        self.words.get(index).map_or(1, |&(_, line)| line)
    }

    /// An error at the line of the word read last.
    pub fn error(&self, message: impl Into<String>) -> Error {
        Error::at_line(self.path, self.line(), message)
    }

    /// The next word, or `None` at the end of the file.
    pub fn next_word(&mut self) -> Option<&'a str> {
        let word = self.peek()?;
        self.next += 1;
        Some(word)
    }

    /// The next word, which must exist: `what` says what was expected.
    pub fn word(&mut self, what: &str) -> Result<&'a str> {
        self.next_word()
            .ok_or_else(|| self.error(format!("unexpected end of file: expected {what}")))
    }

    pub fn keyword(&mut self, expected: &str) -> Result<()> {
        let word = self.word(&format!("'{expected}'"))?;
        if word == expected {
            Ok(())
        } else {
            Err(self.error(format!("expected '{expected}', found '{word}'")))
        }
    }

    /// A finite number.
    pub fn number(&mut self, what: &str) -> Result<f32> {
        let word = self.word(what)?;
        match word.parse::<f32>() {
            Ok(x) if x.is_finite() => Ok(x),
            Ok(_) => Err(self.error(format!("{what} is not finite: '{word}'"))),
            Err(_) => Err(self.error(format!("expected {what} (a number), found '{word}'"))),
        }
    }

    pub fn vec3(&mut self, what: &str) -> Result<Vec3> {
        Ok(Vec3::new(
            self.number(what)?,
            self.number(what)?,
            self.number(what)?,
        ))
    }

    pub fn integer(&mut self, what: &str) -> Result<i64> {
        let word = self.word(what)?;
        word.parse::<i64>()
            .map_err(|_| self.error(format!("expected {what} (an integer), found '{word}'")))
    }

    /// An index into a table of `len` entries.
    pub fn index(&mut self, what: &str, len: usize) -> Result<usize> {
        let i = self.integer(what)?;
        usize::try_from(i)
            .ok()
            .filter(|&i| i < len)
            .ok_or_else(|| self.error(format!("{what} {i} is out of range (0..{len})")))
    }

    /// A count of items that take at least `words_each` words each. Counts the rest of the file
    /// cannot hold are refused before anything is allocated for them.
    pub fn count(&mut self, what: &str, words_each: usize) -> Result<usize> {
        let n = self.integer(what)?;
        let n = usize::try_from(n).map_err(|_| self.error(format!("{what} {n} is negative")))?;
        if n.saturating_mul(words_each) > self.remaining() {
            return Err(self.error(format!(
                "{what} {n} is more than the rest of the file holds"
            )));
        }
        Ok(n)
    }

    /// Whether the next word is a number (optional arguments, like a light's colour).
    pub fn next_is_number(&self) -> bool {
        self.peek().is_some_and(|w| w.parse::<f32>().is_ok())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_carry_lines_and_comments_are_skipped() {
        let text = "a 1 # comment 2\n% whole line\n\n  b 3.5 % trailing\r\nc";
        let mut t = Tokens::new(Path::new("x.aff"), text);
        assert_eq!(t.word("a").unwrap(), "a");
        assert_eq!(t.integer("n").unwrap(), 1);
        assert_eq!(t.line(), 1);
        assert_eq!(t.word("b").unwrap(), "b");
        assert_eq!(t.line(), 4);
        assert_eq!(t.number("x").unwrap(), 3.5);
        assert_eq!(t.word("c").unwrap(), "c");
        assert_eq!(t.line(), 5);
        assert!(t.next_word().is_none());
        let err = t.word("more").unwrap_err().to_string();
        assert_eq!(err, "x.aff:5: unexpected end of file: expected more");
        // A byte-order mark was once part of the first word ("unknown NFF command '\u{feff}p'").
        let mut t = Tokens::new(Path::new("bom.nff"), "\u{feff}p 3\n");
        assert_eq!(t.word("p").unwrap(), "p");
        assert_eq!((t.integer("n").unwrap(), t.line()), (3, 1));
    }

    #[test]
    fn bad_numbers_and_counts_are_errors_at_their_line() {
        let mut t = Tokens::new(Path::new("f.nff"), "p 3\n1 nan 2\n");
        t.word("p").unwrap();
        assert!(t.count("vertex count", 9).is_err());
        let mut t = Tokens::new(Path::new("f.nff"), "1\nnan\n7\n");
        t.number("x").unwrap();
        let err = t.number("y").unwrap_err().to_string();
        assert_eq!(err, "f.nff:2: y is not finite: 'nan'");
        let err = t.index("vertex index", 5).unwrap_err().to_string();
        assert_eq!(err, "f.nff:3: vertex index 7 is out of range (0..5)");
    }
}
