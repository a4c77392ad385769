//! The report's pages as HTML: each Markdown page rendered beside itself (tables, pictures
//! inline, links to other pages' `.md` turned to their `.html`), so a reader who opens the
//! report in a browser (`index.html`) reads every page with its pictures.

use pulldown_cmark::{CowStr, Event, Options, Parser, Tag};

/// A relative link to a page's Markdown (`name.md`, `name.md#anchor`) turned to its HTML.
fn html_link(dest: CowStr<'_>) -> CowStr<'_> {
    if dest.contains("://") {
        return dest;
    }
    let (path, anchor) = dest.split_once('#').map_or((&*dest, None), |(p, a)| (p, Some(a)));
    match path.strip_suffix(".md") {
        Some(stem) if !stem.is_empty() && !stem.contains('/') => {
            let stem = if stem == "REPORT" { "index" } else { stem };
            CowStr::from(match anchor {
                Some(a) => format!("{stem}.html#{a}"),
                None => format!("{stem}.html"),
            })
        }
        _ => dest,
    }
}

/// Markdown to HTML (tables on), links between pages turned to the pages' HTML.
pub fn markdown_to_html(md: &str) -> String {
    let parser = Parser::new_ext(md, Options::ENABLE_TABLES).map(|event| match event {
        Event::Start(Tag::Link { link_type, dest_url, title, id }) => {
            Event::Start(Tag::Link { link_type, dest_url: html_link(dest_url), title, id })
        }
        other => other,
    });
    let mut body = String::new();
    pulldown_cmark::html::push_html(&mut body, parser);
    body
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

/// A whole HTML page of the Markdown `md`, titled `title`.
pub fn html_page(title: &str, md: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n{}</body>\n</html>\n",
        escape(&title.replace('`', "")),
        markdown_to_html(md)
    )
}

/// The pages' style: readable width, tables that scroll instead of overflowing, pictures that fit.
const STYLE: &str = "body{font-family:sans-serif;max-width:1200px;margin:1em auto;padding:0 1em;line-height:1.45}\
table{border-collapse:collapse;display:block;overflow-x:auto;font-size:0.9em}\
th,td{border:1px solid #ccc;padding:2px 6px;text-align:left}\
img{max-width:100%}code{background:#f3f3f3}";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pages_link_to_pages_and_show_their_pictures() {
        let md = "[isolab report](REPORT.md) › [peers](peers.md#ratios) and [data](data/peers.json), \
                  [out](https://example.org/a.md)\n\n![chart](figures/x.png)\n\n| a |\n|---|\n| 1 |\n";
        let html = html_page("A <page>", md);
        assert!(html.contains("href=\"index.html\""), "{html}");
        assert!(html.contains("href=\"peers.html#ratios\""), "{html}");
        assert!(html.contains("href=\"data/peers.json\""), "{html}");
        assert!(html.contains("href=\"https://example.org/a.md\""), "{html}");
        assert!(html.contains("<img src=\"figures/x.png\" alt=\"chart\""), "{html}");
        assert!(html.contains("<table>") && html.contains("<title>A &lt;page&gt;</title>"), "{html}");
        assert!(html_page("Peers (`peers`)", "").contains("<title>Peers (peers)</title>"));
    }
}
