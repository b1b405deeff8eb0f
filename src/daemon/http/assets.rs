//! The page's files, compiled into the binary (`include_bytes!`): the only paths served besides
//! `/events`. No path ever reaches the file system.
//!
//! `assets/web/` is the page (HTML, its script and style); `assets/vendor/uplot/` is uPlot
//! (MIT, ~50 KB minified: the small, maintained canvas plotting library the charts use),
//! vendored as npm publishes it (`npm pack uplot`, `dist/uPlot.iife.min.js`,
//! `dist/uPlot.min.css`, `LICENSE`).

/// One embedded file.
#[derive(Debug, Clone, Copy)]
pub struct Asset {
    /// Its `Content-Type`.
    pub content_type: &'static str,
    /// Its bytes.
    pub body: &'static [u8],
}

const HTML: &str = "text/html; charset=utf-8";
const JS: &str = "text/javascript; charset=utf-8";
const CSS: &str = "text/css; charset=utf-8";
const TEXT: &str = "text/plain; charset=utf-8";

/// The table: URL path, content type, bytes.
const ASSETS: &[(&str, &str, &[u8])] = &[
    ("/", HTML, include_bytes!("../../../assets/web/index.html")),
    (
        "/index.html",
        HTML,
        include_bytes!("../../../assets/web/index.html"),
    ),
    ("/app.js", JS, include_bytes!("../../../assets/web/app.js")),
    (
        "/app.css",
        CSS,
        include_bytes!("../../../assets/web/app.css"),
    ),
    (
        "/vendor/uplot/uPlot.iife.min.js",
        JS,
        include_bytes!("../../../assets/vendor/uplot/uPlot.iife.min.js"),
    ),
    (
        "/vendor/uplot/uPlot.min.css",
        CSS,
        include_bytes!("../../../assets/vendor/uplot/uPlot.min.css"),
    ),
    (
        "/vendor/uplot/LICENSE",
        TEXT,
        include_bytes!("../../../assets/vendor/uplot/LICENSE"),
    ),
];

/// The embedded file at `path` (exact match), if there is one.
pub fn get(path: &str) -> Option<Asset> {
    ASSETS
        .iter()
        .find(|a| a.0 == path)
        .map(|&(_, content_type, body)| Asset { content_type, body })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_the_table_is_served() {
        assert!(get("/").unwrap().content_type.starts_with("text/html"));
        assert!(get("/app.js").is_some());
        assert!(get("/vendor/uplot/uPlot.iife.min.js").unwrap().body.len() > 10_000);
        for p in [
            "",
            "/../Cargo.toml",
            "/etc/passwd",
            "/assets/web/index.html",
            "//app.js",
        ] {
            assert!(get(p).is_none(), "{p}");
        }
    }
}
