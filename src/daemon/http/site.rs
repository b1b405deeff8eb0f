//! What one server serves, for a page other than the live page (`propid fleet`): its own file
//! table, and *named event streams* besides `/events`, each with its own clients and history
//! under the same rules as `/events` (bounded queues, slow clients dropped, `max_clients`
//! each, a late browser gets the history first).
//!
//! The live page is [`Site::LIVE`]: the files of [`super::assets`] and no named stream. The
//! fleet page maps `/stand/NAME/events` to the stream `NAME`, which
//! [`HttpSink::send_to`] creates at its first line; a path naming a stream not created yet is
//! `404`.

use std::sync::Arc;

use super::assets::{self, Asset};
use super::{lock, HttpSink, Kind, Shared, Stream};

/// A server's paths: its files and its named streams.
#[derive(Clone, Copy)]
pub struct Site {
    /// The embedded file at a path (exact match), if any.
    pub asset: fn(&str) -> Option<Asset>,
    /// The stream a path names (besides `/events`), if it names one.
    pub stream: fn(&str) -> Option<&str>,
}

/// No named stream: only `/events`.
pub fn no_stream(_: &str) -> Option<&str> {
    None
}

impl Site {
    /// The live page: [`assets::get`], only `/events`.
    pub const LIVE: Site = Site {
        asset: assets::get,
        stream: no_stream,
    };
}

impl Shared {
    /// The named stream `path` names, when it exists.
    pub(super) fn find_stream(&self, path: &str) -> Option<Arc<Stream>> {
        let name = (self.site.stream)(path)?;
        let named = lock(&self.named);
        named.iter().find(|s| s.0 == name).map(|s| s.1.clone())
    }

    /// The named stream `name`, created if it is not yet.
    fn stream_or_add(&self, name: &str) -> Arc<Stream> {
        let mut named = lock(&self.named);
        if let Some(s) = named.iter().find(|s| s.0 == name) {
            return s.1.clone();
        }
        let s = Arc::new(Stream::default());
        named.push((name.to_string(), s.clone()));
        s
    }
}

impl HttpSink {
    /// Queues `line` to the clients of the named stream `stream` (created at its first line),
    /// as [`HttpSink::send`] does for `/events`; after the sink closed, nothing.
    pub fn send_to(&self, stream: &str, kind: Kind, line: &str) {
        let sh = &self.shared;
        if !sh.closing.load(std::sync::atomic::Ordering::Relaxed) {
            sh.send(&sh.stream_or_add(stream), kind, line);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{BufRead, BufReader, Write};
    use std::net::TcpStream;
    use std::time::Duration;

    fn asset(path: &str) -> Option<Asset> {
        match path {
            "/" => assets::get("/app.css"),
            _ => None,
        }
    }

    fn stream(path: &str) -> Option<&str> {
        path.strip_prefix("/s/")?.strip_suffix("/events")
    }

    fn get(s: &HttpSink, path: &str) -> BufReader<TcpStream> {
        let mut c = TcpStream::connect(s.addr()).unwrap();
        c.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        write!(c, "GET {path} HTTP/1.1\r\nHost: {}\r\n\r\n", s.addr()).unwrap();
        BufReader::new(c)
    }

    fn status(s: &HttpSink, path: &str) -> String {
        let mut line = String::new();
        get(s, path).read_line(&mut line).unwrap();
        line
    }

    /// Another site's table replaces the live page's; each named stream gets its own lines.
    #[test]
    fn a_site_serves_its_table_and_its_named_streams() {
        let site = Site { asset, stream };
        let s = HttpSink::bind_site("127.0.0.1:0".parse().unwrap(), 16, 4, site).unwrap();
        assert!(status(&s, "/").contains(" 200 "));
        assert!(status(&s, "/app.js").contains(" 404 "));
        assert!(
            status(&s, "/s/a/events").contains(" 404 "),
            "no stream a yet"
        );
        s.send_to("a", Kind::State("model"), r#"{"n":"a1"}"#);
        s.send_to("b", Kind::State("model"), r#"{"n":"b1"}"#);
        s.send(Kind::State("fleet"), r#"{"n":"all"}"#);
        let mut c = get(&s, "/s/a/events");
        let mut lines = Vec::new();
        while !lines.iter().any(|l: &String| l.starts_with("data:")) {
            let mut l = String::new();
            c.read_line(&mut l).unwrap();
            lines.push(l);
        }
        assert!(
            lines.iter().any(|l| l.contains("text/event-stream")),
            "{lines:?}"
        );
        assert_eq!(lines.last().unwrap().trim(), r#"data: {"n":"a1"}"#);
        s.send_to("b", Kind::Log, r#"{"n":"b2"}"#);
        s.send_to("a", Kind::Log, r#"{"n":"a2"}"#);
        let mut l = String::new();
        while !l.starts_with("data:") {
            l.clear();
            c.read_line(&mut l).unwrap();
        }
        assert_eq!(l.trim(), r#"data: {"n":"a2"}"#);
    }
}
