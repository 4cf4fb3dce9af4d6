//! The markdown raylab itself writes (tables.md, summary.md), read back as blocks: headings,
//! paragraphs, pipe tables and fenced code. Enough to turn those files into HTML and to look up a
//! table cell by table title, row label and column label; not a general markdown parser.

#[derive(Clone, Debug, PartialEq)]
pub enum Block {
    Heading { level: usize, text: String },
    Paragraph(String),
    Table(Table),
    Code(String),
}

#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// The nearest heading above the table (empty when none).
    pub title: String,
    pub header: Vec<String>,
    /// Per column: right-aligned (`---:`).
    pub right: Vec<bool>,
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// The cell of the row whose first cell is `row` and the column headed `column`.
    pub fn cell(&self, row: &str, column: &str) -> Option<&str> {
        let c = self.header.iter().position(|h| h == column)?;
        let r = self
            .rows
            .iter()
            .find(|r| r.first().map(String::as_str) == Some(row))?;
        r.get(c).map(String::as_str)
    }
}

/// Splits `| a | b \| c |` into `["a", "b | c"]`.
fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|');
    let inner = inner.strip_suffix('|').unwrap_or(inner);
    let mut out = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                out.last_mut().expect("never empty").push('|');
                chars.next();
            }
            '|' => out.push(String::new()),
            c => out.last_mut().expect("never empty").push(c),
        }
    }
    out.into_iter().map(|c| c.trim().to_string()).collect()
}

fn is_delimiter_row(line: &str) -> bool {
    let t = line.trim();
    t.starts_with('|') && t.contains('-') && t.chars().all(|c| "|-: ".contains(c))
}

/// The blocks of `text`, in order.
pub fn parse(text: &str) -> Vec<Block> {
    let lines: Vec<&str> = text.lines().collect();
    let mut blocks = Vec::new();
    let mut title = String::new();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let t = line.trim();
        if t.is_empty() {
            i += 1;
        } else if t.starts_with("```") {
            let end = (i + 1..lines.len())
                .find(|&j| lines[j].trim().starts_with("```"))
                .unwrap_or(lines.len());
            blocks.push(Block::Code(lines[i + 1..end].join("\n")));
            i = end + 1;
        } else if let Some(level) = heading_level(t) {
            title = t[level..].trim().to_string();
            blocks.push(Block::Heading {
                level,
                text: title.clone(),
            });
            i += 1;
        } else if t.starts_with('|') && lines.get(i + 1).is_some_and(|l| is_delimiter_row(l)) {
            let header = cells(t);
            let right = cells(lines[i + 1])
                .iter()
                .map(|d| d.ends_with(':') && !d.starts_with(':'))
                .collect();
            let mut rows = Vec::new();
            i += 2;
            while i < lines.len() && lines[i].trim().starts_with('|') {
                rows.push(cells(lines[i]));
                i += 1;
            }
            blocks.push(Block::Table(Table {
                title: title.clone(),
                header,
                right,
                rows,
            }));
        } else {
            let start = i;
            while i < lines.len() && !lines[i].trim().is_empty() && !starts_block(lines[i]) {
                i += 1;
            }
            blocks.push(Block::Paragraph(lines[start..i.max(start + 1)].join("\n")));
            i = i.max(start + 1);
        }
    }
    blocks
}

fn heading_level(t: &str) -> Option<usize> {
    let level = t.chars().take_while(|&c| c == '#').count();
    ((1..=6).contains(&level) && t[level..].starts_with(' ')).then_some(level)
}

fn starts_block(line: &str) -> bool {
    let t = line.trim();
    t.starts_with('|') || t.starts_with("```") || heading_level(t).is_some()
}

/// The tables among `blocks`.
pub fn tables(blocks: &[Block]) -> impl Iterator<Item = &Table> {
    blocks.iter().filter_map(|b| match b {
        Block::Table(t) => Some(t),
        _ => None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str =
        "# t: paper vs ours\n\n## Table 1: tests\n\nunder the title\nsecond line\n\n\
        | scene | ours | a \\| b |\n|---|---:|:---:|\n| toys | 1.50 | – |\n| hand | 2 | x |\n\n\
        ```\ncode | here\n```\n## Other\n| k | v |\n|---|---|\n| a | 1 |\n";

    #[test]
    fn headings_paragraphs_tables_and_code_come_back_in_order() {
        let blocks = parse(TEXT);
        assert_eq!(blocks.len(), 7, "{blocks:#?}");
        assert_eq!(
            blocks[0],
            Block::Heading {
                level: 1,
                text: "t: paper vs ours".into()
            }
        );
        assert_eq!(
            blocks[2],
            Block::Paragraph("under the title\nsecond line".into())
        );
        let Block::Table(table) = &blocks[3] else {
            panic!("{:?}", blocks[3])
        };
        assert_eq!(table.title, "Table 1: tests");
        assert_eq!(table.header, ["scene", "ours", "a | b"]);
        assert_eq!(table.right, [false, true, false]);
        assert_eq!(table.rows.len(), 2);
        assert_eq!(table.cell("toys", "ours"), Some("1.50"));
        assert_eq!(table.cell("hand", "a | b"), Some("x"));
        assert_eq!(table.cell("cat", "ours"), None);
        assert_eq!(table.cell("toys", "theirs"), None);
        assert_eq!(blocks[4], Block::Code("code | here".into()));
        let last: Vec<&Table> = tables(&blocks).collect();
        assert_eq!(last.len(), 2);
        assert_eq!(last[1].title, "Other");
        assert_eq!(last[1].cell("a", "v"), Some("1"));
    }
}
