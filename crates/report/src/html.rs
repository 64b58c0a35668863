//! The page's frame: escaping, the style sheet (one, inline), tables and figures with the numbers a
//! reader (or a test) reads back.

use std::fmt::Write;

/// `s` safe inside HTML text and attribute values.
pub(crate) fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// The style sheet: a readable column on a laptop, full width on a phone, tables that scroll sideways
/// rather than squeeze, charts as wide as the column.
const STYLE: &str = "
body{font:15px/1.45 system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;color:#1b1b1b;margin:0;background:#f6f6f4}
main{max-width:980px;margin:0 auto;padding:12px 16px 48px;background:#fff}
h1{font-size:1.45em;margin:.4em 0}h2{font-size:1.2em;margin:1.6em 0 .4em;border-bottom:1px solid #ddd}
h3{font-size:1.02em;margin:1.1em 0 .3em}
p.lead{font-size:1.08em}
.verdict{border-left:5px solid #1f5fbf;padding:.5em .8em;background:#eef3fb}
.refused{border-left:5px solid #c0392b;padding:.5em .8em;background:#fbeeee}
.warn{border-left:5px solid #d9730d;padding:.3em .8em;background:#fdf3ea;margin:.3em 0}
.scroll{overflow-x:auto;-webkit-overflow-scrolling:touch}
table{border-collapse:collapse;margin:.4em 0;font-variant-numeric:tabular-nums}
th,td{padding:3px 8px;border-bottom:1px solid #e4e4e4;text-align:right;white-space:nowrap}
th:first-child,td:first-child{text-align:left}
td.text{text-align:left;white-space:normal;min-width:16em}
code{font-size:.92em;background:#f0f0f0;padding:1px 4px;border-radius:3px;word-break:break-all}
.grid2{display:grid;grid-template-columns:repeat(auto-fill,minmax(300px,1fr));gap:8px}
.wide2{display:grid;grid-template-columns:repeat(auto-fill,minmax(420px,1fr));gap:8px}
@media (max-width:460px){.wide2{grid-template-columns:1fr}}
@media (max-width:600px){table.hd td:nth-child(3),table.hd td:nth-child(4),table.hd td:nth-child(6),table.hd th:nth-child(3),table.hd th:nth-child(4),table.hd th:nth-child(6){display:none}}
svg.chart{width:100%;height:auto;display:block}
svg .ax{stroke:#333;font-size:12px}svg .ax text{stroke:none;fill:#333}svg .ax rect{stroke:#333}
svg .grid{stroke:#e6e6e6}svg .ct{font-size:14px;font-weight:600}svg .lg,svg .bl{font-size:12px}
figure{margin:.6em 0}figcaption{font-size:.9em;color:#555}
small{color:#555}
";

/// The page around `body`: a complete HTML document with its style inline and nothing fetched.
pub(crate) fn document(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><meta name=\"viewport\" content=\"width=device-width, initial-scale=1\"><title>{}</title><style>{STYLE}</style></head><body><main>\n{body}\n</main></body></html>\n",
        escape(title)
    )
}

/// A number as the report prints it, in a cell a test reads back: `data-figure` names it.
pub(crate) fn figure(name: &str, value: f64, decimals: usize) -> String {
    format!(r#"<td data-figure="{}">{value:.decimals$}</td>"#, escape(name))
}

/// A table: its header row and rows of ready cells (`<td>…</td>` each).
pub(crate) fn table(out: &mut String, header: &[&str], rows: &[Vec<String>]) {
    table_of_class(out, "", header, rows);
}

/// [`table`] with a class (the held-out table's: columns that a phone's width hides).
pub(crate) fn table_of_class(out: &mut String, class: &str, header: &[&str], rows: &[Vec<String>]) {
    let _ = write!(out, "<div class=\"scroll\"><table class=\"{}\"><thead><tr>", escape(class));
    for h in header {
        let _ = write!(out, "<th>{}</th>", escape(h));
    }
    out.push_str("</tr></thead><tbody>");
    for row in rows {
        out.push_str("<tr>");
        for cell in row {
            out.push_str(cell);
        }
        out.push_str("</tr>");
    }
    out.push_str("</tbody></table></div>");
}

/// A plain text cell.
pub(crate) fn cell(text: &str) -> String {
    format!("<td>{}</td>", escape(text))
}

/// A text cell that wraps (a reason, a remedy).
pub(crate) fn text_cell(text: &str) -> String {
    format!("<td class=\"text\">{}</td>", escape(text))
}

/// A number cell with `decimals` decimals; `—` for none.
pub(crate) fn number(value: Option<f64>, decimals: usize) -> String {
    match value {
        Some(v) if v.is_finite() => format!("<td>{v:.decimals$}</td>"),
        _ => "<td>—</td>".to_string(),
    }
}

/// A chart with its caption.
pub(crate) fn chart(out: &mut String, svg: &str, caption: &str) {
    let _ = write!(out, "<figure>{svg}<figcaption>{}</figcaption></figure>", escape(caption));
}

#[cfg(test)]
mod tests {
    use super::escape;

    #[test]
    fn text_cannot_become_markup() {
        assert_eq!(escape("<a href=\"x\">&'"), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;");
    }
}
