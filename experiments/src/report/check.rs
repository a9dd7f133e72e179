//! The no-network check: finds references to resources outside the report file.

/// Every place in `html` that would make a browser reach the network: absolute URLs with a
/// scheme other than `data:` (`http:`, `https:`, `ftp:`, `ws:`, `wss:`, ...) and
/// protocol-relative `//host` references in `src`, `href`, `action` or CSS `url(...)`.
/// An empty result means the page opens offline.
///
/// # Example
/// ```
/// use experiments::report::find_external_urls;
///
/// assert!(find_external_urls(r#"<img src="data:image/png;base64,AAAA">"#).is_empty());
/// assert_eq!(find_external_urls(r#"<img src="https://example.org/a.png">"#).len(), 1);
/// ```
#[must_use]
pub fn find_external_urls(html: &str) -> Vec<String> {
    let lower = html.to_ascii_lowercase();
    let mut found = Vec::new();
    for scheme in ["http:", "https:", "ftp:", "ws:", "wss:", "file:"] {
        let mut from = 0;
        while let Some(i) = lower[from..].find(scheme) {
            let at = from + i;
            // `xhttp:` is not a scheme; require a non-alphanumeric character before it.
            let boundary = at == 0 || !lower.as_bytes()[at - 1].is_ascii_alphanumeric();
            if boundary {
                found.push(snippet(html, at));
            }
            from = at + scheme.len();
        }
    }
    for attr in ["src=", "href=", "action=", "url("] {
        let mut from = 0;
        while let Some(i) = lower[from..].find(attr) {
            let at = from + i + attr.len();
            let rest = lower[at..].trim_start_matches(['"', '\'', ' ']);
            if rest.starts_with("//") {
                found.push(snippet(html, at));
            }
            from = at;
        }
    }
    found
}

/// Up to 60 characters of `html` from byte `at` (on a character boundary).
fn snippet(html: &str, at: usize) -> String {
    html[at..].chars().take(60).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_schemes_and_protocol_relative_references() {
        let page = r#"<link href="//cdn.example/x.css"><script src='HTTPS://a.b/c.js'></script>
            <div style="background:url( //x/y.png)"></div><a href="ftp://f">f</a>"#;
        assert_eq!(
            find_external_urls(page).len(),
            4,
            "{:?}",
            find_external_urls(page)
        );
    }

    #[test]
    fn data_uris_and_plain_text_pass() {
        let page = r##"<img src="data:image/png;base64,iVBOR"><p>relMSE: 1e-3 // comment</p>
            <a href="#metrics">x</a> <code>xhttp:</code>"##;
        assert!(find_external_urls(page).is_empty());
    }
}
