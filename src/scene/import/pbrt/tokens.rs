//! pbrt-v4's lexical layer: bare words (directive names, numbers, `true`/`false`), quoted strings
//! with pbrt's escapes, `[` and `]`, and `#` comments to the end of the line. Tokens are read one at
//! a time from the file's text (nothing is collected, so a large mesh costs no token list), each
//! with the line it starts on, so every later error can name it.

use super::super::{shown, Location};
use anyhow::{bail, Result};
use std::rc::Rc;

#[derive(Clone, Debug, PartialEq)]
pub enum Token {
    /// A directive name, a number, or `true`/`false`.
    Word(String),
    /// A quoted string, unescaped.
    Quoted(String),
    Open,
    Close,
}

impl Token {
    /// How the token reads in a message.
    pub fn describe(&self) -> String {
        match self {
            Token::Word(w) => format!("'{}'", shown(w)),
            Token::Quoted(s) => format!("\"{}\"", shown(s)),
            Token::Open => "'['".to_owned(),
            Token::Close => "']'".to_owned(),
        }
    }
}

/// The tokens of one file, with one token of look-ahead.
pub struct Tokens<'t> {
    text: &'t str,
    position: usize,
    line: u32,
    file: Rc<str>,
    peeked: Option<(Token, Location)>,
}

impl<'t> Tokens<'t> {
    pub fn new(text: &'t str, file: Rc<str>) -> Self {
        Tokens { text, position: 0, line: 1, file, peeked: None }
    }

    /// Where the reading stands (the line after the last token read), for "the file ends" errors.
    pub fn here(&self) -> Location {
        Location { file: self.file.clone(), line: self.line }
    }

    /// The next token without taking it.
    pub fn peek(&mut self) -> Result<Option<&(Token, Location)>> {
        if self.peeked.is_none() {
            self.peeked = self.read()?;
        }
        Ok(self.peeked.as_ref())
    }

    pub fn next(&mut self) -> Result<Option<(Token, Location)>> {
        match self.peeked.take() {
            Some(t) => Ok(Some(t)),
            None => self.read(),
        }
    }

    fn read(&mut self) -> Result<Option<(Token, Location)>> {
        let bytes = self.text.as_bytes();
        // White space and comments.
        loop {
            match bytes.get(self.position) {
                None => return Ok(None),
                Some(b'\n') => {
                    self.line += 1;
                    self.position += 1;
                }
                Some(b) if b.is_ascii_whitespace() => self.position += 1,
                Some(b'#') => {
                    while bytes.get(self.position).is_some_and(|&b| b != b'\n') {
                        self.position += 1;
                    }
                }
                Some(_) => break,
            }
        }
        let at = self.here();
        let start = self.position;
        let token = match bytes[start] {
            b'[' => {
                self.position += 1;
                Token::Open
            }
            b']' => {
                self.position += 1;
                Token::Close
            }
            b'"' => Token::Quoted(self.quoted(&at)?),
            _ => {
                while bytes
                    .get(self.position)
                    .is_some_and(|&b| !(b.is_ascii_whitespace() || matches!(b, b'"' | b'[' | b']' | b'#')))
                {
                    self.position += 1;
                }
                // Stops only at ASCII bytes, so the slice ends on a character boundary.
                Token::Word(self.text[start..self.position].to_owned())
            }
        };
        Ok(Some((token, at)))
    }

    /// The string starting at the opening quote under the cursor; a string ends on its line.
    fn quoted(&mut self, at: &Location) -> Result<String> {
        let mut out = String::new();
        let mut chars = self.text[self.position + 1..].char_indices();
        loop {
            let Some((i, c)) = chars.next() else {
                bail!("{at}: unterminated string (the file ends before its closing quote)")
            };
            match c {
                '"' => {
                    self.position += 1 + i + 1;
                    return Ok(out);
                }
                '\n' => bail!("{at}: unterminated string (a newline before its closing quote)"),
                '\\' => {
                    let Some((_, e)) = chars.next() else {
                        bail!("{at}: unterminated string (the file ends in an escape)")
                    };
                    out.push(match e {
                        'n' => '\n',
                        't' => '\t',
                        'r' => '\r',
                        'b' => '\u{8}',
                        'f' => '\u{c}',
                        '\\' | '"' | '\'' => e,
                        '\n' => bail!("{at}: unterminated string (a newline before its closing quote)"),
                        other => bail!("{at}: unknown escape \\{other} in a string"),
                    });
                }
                c => out.push(c),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(text: &str) -> Result<Vec<(Token, u32)>> {
        let mut t = Tokens::new(text, Rc::from("t.pbrt"));
        let mut out = vec![];
        while let Some((token, at)) = t.next()? {
            out.push((token, at.line));
        }
        Ok(out)
    }

    #[test]
    fn words_strings_brackets_and_comments_carry_their_lines() {
        let tokens =
            all("LookAt 0 0 5 # a comment \"not a string\n  Shape \"sphere\" \"float radius\" [2.5]\n\"a\\\"b\"")
                .unwrap();
        let words: Vec<_> = tokens.iter().map(|(t, l)| (t.describe(), *l)).collect();
        assert_eq!(words[0], ("'LookAt'".to_owned(), 1));
        assert_eq!(words[4], ("'Shape'".to_owned(), 2));
        assert_eq!(tokens[5].0, Token::Quoted("sphere".into()));
        assert_eq!(
            (&tokens[7].0, &tokens[8].0, &tokens[9].0),
            (&Token::Open, &Token::Word("2.5".into()), &Token::Close)
        );
        assert_eq!(tokens[10], (Token::Quoted("a\"b".into()), 3));
    }

    #[test]
    fn an_unterminated_string_names_its_line() {
        let e = all("Shape\n\"sphere").unwrap_err().to_string();
        assert!(e.starts_with("t.pbrt:2: unterminated string"), "{e}");
        let e = all("Shape \"sph\nere\"").unwrap_err().to_string();
        assert!(e.starts_with("t.pbrt:1: unterminated string"), "{e}");
    }
}
