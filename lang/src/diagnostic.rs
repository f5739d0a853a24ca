//! Input errors as `file:line:col: message`, the source line, and a caret.

use std::fmt;

/// A byte range in the source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Span {
    pub start: usize,
    pub end: usize,
}

impl From<pest::Span<'_>> for Span {
    fn from(s: pest::Span<'_>) -> Self {
        Span { start: s.start(), end: s.end() }
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Diagnostic {
    pub span: Span,
    pub message: String,
}

impl Diagnostic {
    pub fn new(span: Span, message: impl Into<String>) -> Self {
        Diagnostic { span, message: message.into() }
    }

    /// 1-based line and column (in characters) of the start of the span.
    pub fn line_col(&self, source: &str) -> (usize, usize) {
        let at = self.span.start.min(source.len());
        let before = &source[..at];
        let line = before.matches('\n').count() + 1;
        let col = before.rsplit('\n').next().unwrap_or("").chars().count() + 1;
        (line, col)
    }

    /// The full report: `file:line:col: message`, then the line and a caret under the column.
    pub fn render(&self, file: &str, source: &str) -> Rendered {
        let (line, col) = self.line_col(source);
        let text = source.lines().nth(line - 1).unwrap_or("").to_string();
        Rendered { head: format!("{file}:{line}:{col}: {}", self.message), text, col }
    }
}

pub struct Rendered {
    pub head: String,
    text: String,
    col: usize,
}

impl fmt::Display for Rendered {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let pad: String = self.text.chars().take(self.col - 1).map(|c| if c == '\t' { '\t' } else { ' ' }).collect();
        write!(f, "{}\n  {}\n  {pad}^", self.head, self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn position_is_one_based_in_characters() {
        let src = "ab\ncdé fg\n";
        let d = Diagnostic::new(Span { start: 8, end: 9 }, "x");
        assert_eq!(d.line_col(src), (2, 5));
        assert_eq!(d.render("f", src).to_string(), "f:2:5: x\n  cdé fg\n      ^");
    }
}
