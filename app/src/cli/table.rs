//! Markdown tables for the reports: a header, then rows of cells, with the separator line
//! written once. Every report table goes through here, so they all read the same.

use std::fmt::{Display, Write as _};

/// A Markdown table being written.
pub(crate) struct Table {
    columns: usize,
    text: String,
}

impl Table {
    /// A table with these column headers.
    pub(crate) fn new<S: AsRef<str>>(header: &[S]) -> Self {
        let mut t = Self {
            columns: header.len(),
            text: String::new(),
        };
        t.line(header.iter().map(|h| h.as_ref()));
        t.text += "|";
        t.text += &"---|".repeat(header.len());
        t.text += "\n";
        t
    }

    /// One row; as many cells as columns.
    pub(crate) fn row(&mut self, cells: &[&dyn Display]) {
        debug_assert_eq!(cells.len(), self.columns, "cells in a row");
        self.line(cells.iter());
    }

    /// One row of cells already formatted.
    pub(crate) fn row_of<S: Display>(&mut self, cells: impl IntoIterator<Item = S>) {
        self.line(cells);
    }

    fn line<S: Display>(&mut self, cells: impl IntoIterator<Item = S>) {
        self.text += "|";
        for c in cells {
            let _ = write!(self.text, " {c} |");
        }
        self.text += "\n";
    }

    /// The table's Markdown, ending in a newline.
    pub(crate) fn finish(self) -> String {
        self.text
    }
}

/// `**x**`: a count that must be zero, in bold so a non-zero one stands out.
pub(crate) fn bold(x: impl Display) -> String {
    format!("**{x}**")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_table_is_its_header_separator_and_rows() {
        let mut t = Table::new(&["a", "b"]);
        t.row(&[&1, &"x"]);
        t.row_of(["2.5", "y"]);
        assert_eq!(t.finish(), "| a | b |\n|---|---|\n| 1 | x |\n| 2.5 | y |\n");
        assert_eq!(bold(0), "**0**");
    }
}
