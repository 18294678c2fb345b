//! The report's one HTML writer: a [`Report`] is run metadata and [`Section`]s; a section is a
//! heading, paragraphs, rows of figures and tables. Sections are built as data by the code that
//! measures them and written here, with a table of contents, so every section looks alike and a
//! new paper's section is one more [`Section`], not pasted markup.
//!
//! Text is escaped; inline `` `code` `` and `**bold**` are the only markup a paragraph carries.

use std::fmt::Write as _;

/// One image in a row of figures.
#[derive(Clone, Debug)]
pub struct Figure {
    /// Its file, relative to the report.
    pub file: String,
    /// Its caption.
    pub caption: String,
    /// Shown under it: the FLIP colour scale (for heat maps).
    pub scale: bool,
}

impl Figure {
    /// An image and its caption.
    pub fn new(file: impl Into<String>, caption: impl Into<String>) -> Self {
        Figure {
            file: file.into(),
            caption: caption.into(),
            scale: false,
        }
    }

    /// A FLIP heat map, shown with its colour scale.
    pub fn heat_map(file: impl Into<String>, caption: impl Into<String>) -> Self {
        Figure {
            scale: true,
            ..Figure::new(file, caption)
        }
    }
}

/// A table: a header row and rows of cells (plain text).
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// Column headings.
    pub header: Vec<String>,
    /// Rows.
    pub rows: Vec<Vec<String>>,
}

impl Table {
    /// A table with these column headings.
    pub fn new<S: Into<String>>(header: impl IntoIterator<Item = S>) -> Self {
        Table {
            header: header.into_iter().map(Into::into).collect(),
            rows: Vec::new(),
        }
    }

    /// Appends a row.
    pub fn row<S: Into<String>>(&mut self, cells: impl IntoIterator<Item = S>) {
        self.rows.push(cells.into_iter().map(Into::into).collect());
    }
}

/// What a section holds, in order.
#[derive(Clone, Debug)]
enum Block {
    Heading(String),
    Paragraph(String),
    Figures(Vec<Figure>),
    Table(Table),
    Link(String, String),
}

/// One section of the report.
#[derive(Clone, Debug)]
pub struct Section {
    id: String,
    title: String,
    blocks: Vec<Block>,
}

impl Section {
    /// A section with an anchor `id` and a title.
    pub fn new(id: impl Into<String>, title: impl Into<String>) -> Self {
        Section {
            id: id.into(),
            title: title.into(),
            blocks: Vec::new(),
        }
    }

    /// A sub-heading.
    pub fn heading(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Heading(text.into()));
        self
    }

    /// A paragraph (`` `code` `` and `**bold**` allowed).
    pub fn paragraph(&mut self, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Paragraph(text.into()));
        self
    }

    /// A row of figures.
    pub fn figures(&mut self, figures: Vec<Figure>) -> &mut Self {
        self.blocks.push(Block::Figures(figures));
        self
    }

    /// A paragraph that is one link to `href` (a file beside the report).
    pub fn link(&mut self, href: impl Into<String>, text: impl Into<String>) -> &mut Self {
        self.blocks.push(Block::Link(href.into(), text.into()));
        self
    }

    /// A table.
    pub fn table(&mut self, table: Table) -> &mut Self {
        self.blocks.push(Block::Table(table));
        self
    }
}

/// The whole report.
#[derive(Clone, Debug, Default)]
pub struct Report {
    /// Its title.
    pub title: String,
    /// What the run was: version, commit, machine, threads, date (label, value).
    pub metadata: Vec<(String, String)>,
    /// Its sections, in order.
    pub sections: Vec<Section>,
}

/// The FLIP colour scale's image, written beside the report.
pub const SCALE_FILE: &str = "flip-scale.png";

const STYLE: &str = "body{font-family:system-ui,sans-serif;max-width:1150px;margin:2em auto;padding:0 1em;color:#222;line-height:1.45}
table{border-collapse:collapse;margin:1em 0}td,th{border:1px solid #ccc;padding:.3em .6em;text-align:right}
th{background:#f4f4f4}td:first-child,td.text{text-align:left}
.row{display:flex;flex-wrap:wrap;gap:1em;align-items:flex-start}figure{margin:0}figure img{max-width:340px;border:1px solid #ddd;image-rendering:pixelated}
figcaption{font-size:.9em;color:#555;max-width:340px}.scale{display:flex;justify-content:space-between;font-size:.8em;color:#555;max-width:340px}
.scale img{width:100%;height:10px;border:0}nav ol{columns:2}dl.meta{display:grid;grid-template-columns:max-content auto;gap:.2em 1em}dl.meta dt{font-weight:600}dl.meta dd{margin:0}";

impl Report {
    /// The page.
    pub fn to_html(&self) -> String {
        let mut h = String::new();
        let _ = write!(
            h,
            "<!doctype html><html><head><meta charset=utf-8><title>{}</title><style>{STYLE}</style></head><body>\n<h1>{}</h1>\n",
            escape(&self.title),
            escape(&self.title)
        );
        h.push_str("<dl class=meta>");
        for (k, v) in &self.metadata {
            let _ = write!(h, "<dt>{}</dt><dd>{}</dd>", escape(k), escape(v));
        }
        h.push_str("</dl>\n<nav><h2>Contents</h2><ol>");
        for s in &self.sections {
            let _ = write!(h, "<li><a href=\"#{}\">{}</a></li>", s.id, escape(&s.title));
        }
        h.push_str("</ol></nav>\n");
        for s in &self.sections {
            let _ = writeln!(h, "<section id=\"{}\"><h2>{}</h2>", s.id, escape(&s.title));
            for b in &s.blocks {
                write_block(&mut h, b);
            }
            h.push_str("</section>\n");
        }
        h.push_str("</body></html>\n");
        h
    }
}

fn write_block(h: &mut String, b: &Block) {
    match b {
        Block::Heading(t) => {
            let _ = writeln!(h, "<h3>{}</h3>", inline(t));
        }
        Block::Paragraph(t) => {
            let _ = writeln!(h, "<p>{}</p>", inline(t));
        }
        Block::Link(href, t) => {
            let _ = writeln!(h, "<p><a href=\"{}\">{}</a></p>", escape(href), inline(t));
        }
        Block::Figures(fs) => {
            h.push_str("<div class=row>");
            for f in fs {
                let _ = write!(
                    h,
                    "<figure><img src=\"{}\" alt=\"{}\">",
                    escape(&f.file),
                    escape(&f.caption)
                );
                if f.scale {
                    let _ = write!(
                        h,
                        "<div class=scale><img src=\"{SCALE_FILE}\" alt=\"FLIP colour scale\"></div><div class=scale><span>FLIP 0</span><span>0.5</span><span>1</span></div>"
                    );
                }
                let _ = write!(
                    h,
                    "<figcaption>{}</figcaption></figure>",
                    inline(&f.caption)
                );
            }
            h.push_str("</div>\n");
        }
        Block::Table(t) => {
            h.push_str("<table><tr>");
            for c in &t.header {
                let _ = write!(h, "<th>{}</th>", inline(c));
            }
            h.push_str("</tr>");
            for r in &t.rows {
                h.push_str("<tr>");
                for c in r {
                    // Figures align right, words left.
                    let numeric =
                        c.starts_with(|ch: char| ch.is_ascii_digit() || "−-∞.".contains(ch));
                    let class = if numeric { "" } else { " class=text" };
                    let _ = write!(h, "<td{class}>{}</td>", inline(c));
                }
                h.push_str("</tr>");
            }
            h.push_str("</table>\n");
        }
    }
}

/// `text` with `&`, `<`, `>` and `"` escaped.
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            c => out.push(c),
        }
    }
    out
}

/// Escaped text with `` `code` `` and `**bold**` turned into their tags.
fn inline(text: &str) -> String {
    let escaped = escape(text);
    let mut out = String::with_capacity(escaped.len());
    let (mut code, mut bold) = (false, false);
    let mut rest = escaped.as_str();
    while let Some(c) = rest.chars().next() {
        if c == '`' {
            out.push_str(if code { "</code>" } else { "<code>" });
            code = !code;
            rest = &rest[1..];
        } else if !code && rest.starts_with("**") {
            out.push_str(if bold { "</b>" } else { "<b>" });
            bold = !bold;
            rest = &rest[2..];
        } else {
            out.push(c);
            rest = &rest[c.len_utf8()..];
        }
    }
    if code {
        out.push_str("</code>");
    }
    if bold {
        out.push_str("</b>");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sections_are_listed_escaped_and_in_order() {
        let mut a = Section::new("a", "First <one>");
        a.paragraph("Run `trompe demo` for **all** of it & more.");
        let mut t = Table::new(["x", "y"]);
        t.row(["1", "<2>"]);
        a.table(t);
        let mut b = Section::new("b", "Second");
        b.figures(vec![Figure::heat_map("h.png", "error")]);
        let r = Report {
            title: "T".into(),
            metadata: vec![("commit".into(), "abc".into())],
            sections: vec![a, b],
        };
        let html = r.to_html();
        assert!(html.contains("<li><a href=\"#a\">First &lt;one&gt;</a></li><li><a href=\"#b\">"));
        assert!(html.contains("<code>trompe demo</code> for <b>all</b> of it &amp; more."));
        assert!(html.contains("<td>1</td><td class=text>&lt;2&gt;</td>"));
        assert!(html.contains(SCALE_FILE) && html.contains("<dt>commit</dt><dd>abc</dd>"));
        assert!(html.find("id=\"a\"") < html.find("id=\"b\""));
    }
}
