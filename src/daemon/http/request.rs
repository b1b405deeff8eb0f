//! A request's head, read from the connection within fixed bounds and parsed by `httparse`
//! (no request grammar here), and the rules it must pass before it is answered: HTTP/1.x, a
//! `Host` naming this server, no body.

use std::io::{ErrorKind, Read};
use std::net::{IpAddr, SocketAddr};
use std::time::{Duration, Instant};

/// Largest request head read (request line and headers), bytes; a longer one is `431`.
pub const MAX_HEAD: usize = 16 * 1024;

/// Most header fields in a head; more is `431`.
const MAX_HEADERS: usize = 64;

/// What a request asks for, once its head was read and parsed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Head {
    /// The method, as sent.
    pub method: String,
    /// The request target without its query.
    pub path: String,
    /// `Host`, when sent (the last one if repeated: it is then refused, see [`Head::refusal`]).
    pub host: Option<String>,
    /// How many `Host` fields were sent.
    pub hosts: usize,
    /// A `Content-Length` other than `0`, or a `Transfer-Encoding`, was sent.
    pub body: bool,
}

/// Why a connection gets no answer but a refusal (or nothing).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Failure {
    /// The client closed, or failed, before a whole head arrived, or sent nothing in time:
    /// nothing to answer.
    Gone,
    /// The whole head did not arrive in time.
    Timeout,
    /// The head (or its number of fields) is over the limit.
    TooLarge,
    /// Not HTTP/1.0 or HTTP/1.1.
    Version,
    /// Not a request head.
    Malformed,
}

impl Failure {
    /// The status code and reason answered, if any.
    pub fn status(self) -> Option<(u16, &'static str)> {
        match self {
            Failure::Gone => None,
            Failure::Timeout => Some((408, "Request Timeout")),
            Failure::TooLarge => Some((431, "Request Header Fields Too Large")),
            Failure::Version => Some((505, "HTTP Version Not Supported")),
            Failure::Malformed => Some((400, "Bad Request")),
        }
    }
}

/// Reads one request head from `conn` into a buffer of at most [`MAX_HEAD`] bytes, for at most
/// `within` in all (however slowly it comes), and parses it. Whatever follows the head (a
/// body, a pipelined request) is never read.
pub fn read_head(conn: &mut impl ReadTimeout, within: Duration) -> Result<Head, Failure> {
    let deadline = Instant::now() + within;
    let mut buf = vec![0u8; MAX_HEAD];
    let mut len = 0;
    loop {
        // a connection opened ahead of a request that never came (a browser's preconnect)
        // is closed without an answer that it could take for its request's
        let late = if len == 0 {
            Failure::Gone
        } else {
            Failure::Timeout
        };
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() || conn.set_timeout(left).is_err() {
            return Err(late);
        }
        match conn.read(&mut buf[len..]) {
            Ok(0) => return Err(Failure::Gone),
            Ok(n) => len += n,
            Err(e) if e.kind() == ErrorKind::Interrupted => continue,
            Err(e) if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) => {
                return Err(late)
            }
            Err(_) => return Err(Failure::Gone),
        }
        match parse(&buf[..len]) {
            Ok(Some(head)) => return Ok(head),
            Ok(None) if len == buf.len() => return Err(Failure::TooLarge),
            Ok(None) => {}
            Err(f) => return Err(f),
        }
    }
}

/// A reader whose reads can be bounded in time (a `TcpStream`; a test's script).
pub trait ReadTimeout: Read {
    /// Bounds the next reads to `t`.
    fn set_timeout(&mut self, t: Duration) -> std::io::Result<()>;
}

impl ReadTimeout for std::net::TcpStream {
    fn set_timeout(&mut self, t: Duration) -> std::io::Result<()> {
        self.set_read_timeout(Some(t))
    }
}

/// Parses `bytes` as a request head: `None` while it is incomplete.
pub fn parse(bytes: &[u8]) -> Result<Option<Head>, Failure> {
    let mut fields = [httparse::EMPTY_HEADER; MAX_HEADERS];
    let mut req = httparse::Request::new(&mut fields);
    match req.parse(bytes) {
        Ok(httparse::Status::Partial) => Ok(None),
        Ok(httparse::Status::Complete(_)) => {
            let mut head = Head {
                method: req.method.unwrap_or("").to_string(),
                path: req
                    .path
                    .unwrap_or("")
                    .split('?')
                    .next()
                    .unwrap_or("")
                    .into(),
                host: None,
                hosts: 0,
                body: false,
            };
            for h in req.headers.iter() {
                if h.name.eq_ignore_ascii_case("host") {
                    head.hosts += 1;
                    head.host = Some(String::from_utf8_lossy(h.value).trim().to_string());
                } else if h.name.eq_ignore_ascii_case("transfer-encoding")
                    || (h.name.eq_ignore_ascii_case("content-length")
                        && h.value.trim_ascii() != b"0")
                {
                    head.body = true;
                }
            }
            Ok(Some(head))
        }
        Err(httparse::Error::TooManyHeaders) => Err(Failure::TooLarge),
        Err(httparse::Error::Version) => Err(Failure::Version),
        Err(_) => Err(Failure::Malformed),
    }
}

impl Head {
    /// The refusal of a request that names another server or carries a body, if it does.
    pub fn refusal(&self, bound: SocketAddr) -> Option<(u16, &'static str)> {
        let named = self.hosts == 1 && self.host.as_deref().is_some_and(|h| host_ok(h, bound));
        if !named {
            return Some((421, "Misdirected Request"));
        }
        if self.body {
            return Some((413, "Content Too Large"));
        }
        None
    }
}

/// Whether a `Host` value names this server: its port (80 when none is written) with
/// `localhost`, a loopback address, or the address bound (any IP address when the bound one
/// is unspecified, `0.0.0.0` or `::`). A DNS name other than `localhost` never does: a page
/// of another site whose name was made to resolve here (DNS rebinding) still sends its own.
pub fn host_ok(host: &str, bound: SocketAddr) -> bool {
    let (name, port) = match host.strip_prefix('[') {
        Some(v6) => match v6.split_once(']') {
            Some((ip, rest)) => (ip, rest),
            None => return false,
        },
        None => match host.rfind(':') {
            Some(i) => host.split_at(i),
            None => (host, ""),
        },
    };
    let port = match port {
        "" => 80,
        p => match p.strip_prefix(':').map(str::parse::<u16>) {
            Some(Ok(p)) => p,
            _ => return false,
        },
    };
    if port != bound.port() {
        return false;
    }
    if name.eq_ignore_ascii_case("localhost") {
        return true;
    }
    match name.parse::<IpAddr>() {
        Ok(ip) => ip.is_loopback() || ip == bound.ip() || bound.ip().is_unspecified(),
        Err(_) => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn head(text: &str) -> Result<Option<Head>, Failure> {
        parse(text.as_bytes())
    }

    #[test]
    fn a_get_is_parsed_with_its_host_and_without_its_query() {
        let h = head("GET /app.js?x=1 HTTP/1.1\r\nHost: 127.0.0.1:8080\r\n\r\n")
            .unwrap()
            .unwrap();
        assert_eq!(h.method, "GET");
        assert_eq!(h.path, "/app.js");
        assert_eq!(h.host.as_deref(), Some("127.0.0.1:8080"));
        assert!(!h.body);
        assert_eq!(head("GET / HTTP/1.1\r\nHost: x\r\n"), Ok(None));
        assert!(head("GET / HTTP/1.0\r\n\r\n").unwrap().is_some());
    }

    #[test]
    fn other_versions_and_garbage_are_refused() {
        assert_eq!(head("GET / HTTP/2.0\r\n\r\n"), Err(Failure::Version));
        assert_eq!(
            head("PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n"),
            Err(Failure::Version)
        );
        assert_eq!(
            head("GET / HTTP/1.1\r\nHo st: x\r\n\r\n"),
            Err(Failure::Malformed)
        );
        assert_eq!(head("\x16\x03\x01\x02\x00"), Err(Failure::Malformed));
        let many: String = (0..MAX_HEADERS + 1)
            .map(|i| format!("X-{i}: y\r\n"))
            .collect();
        assert_eq!(
            head(&format!("GET / HTTP/1.1\r\n{many}\r\n")),
            Err(Failure::TooLarge)
        );
    }

    #[test]
    fn a_body_is_seen_in_the_head_whatever_its_declared_length() {
        for field in [
            "Content-Length: 100000000000000",
            "Content-Length: 1",
            "Content-Length: 99999999999999999999999999",
            "Content-Length: -1",
            "Transfer-Encoding: chunked",
        ] {
            let h = head(&format!(
                "GET / HTTP/1.1\r\nHost: localhost\r\n{field}\r\n\r\n"
            ))
            .unwrap()
            .unwrap();
            assert!(h.body, "{field}");
            assert_eq!(
                h.refusal("127.0.0.1:80".parse().unwrap()),
                Some((413, "Content Too Large"))
            );
        }
        let h = head("GET / HTTP/1.1\r\nHost: localhost\r\nContent-Length: 0\r\n\r\n")
            .unwrap()
            .unwrap();
        assert_eq!(h.refusal("127.0.0.1:80".parse().unwrap()), None);
    }

    #[test]
    fn only_this_servers_names_pass_the_host_check() {
        let lo: SocketAddr = "127.0.0.1:8080".parse().unwrap();
        for ok in [
            "127.0.0.1:8080",
            "localhost:8080",
            "LocalHost:8080",
            "[::1]:8080",
        ] {
            assert!(host_ok(ok, lo), "{ok}");
        }
        for no in [
            "evil.example:8080",
            "127.0.0.1:8081",
            "127.0.0.1",
            "localhost",
            "127.0.0.1:",
            "127.0.0.1:8080:8080",
            "[::1]",
            "[::1:8080",
            "",
            "10.0.0.2:8080",
            "localhost.:8080",
        ] {
            assert!(!host_ok(no, lo), "{no}");
        }
        let on_80: SocketAddr = "127.0.0.1:80".parse().unwrap();
        assert!(host_ok("localhost", on_80) && host_ok("127.0.0.1", on_80));
        let any: SocketAddr = "0.0.0.0:8080".parse().unwrap();
        assert!(host_ok("192.168.1.7:8080", any));
        assert!(!host_ok("propid.lan:8080", any));
        let one: SocketAddr = "192.168.1.7:8080".parse().unwrap();
        assert!(host_ok("192.168.1.7:8080", one) && !host_ok("192.168.1.8:8080", one));
        // none, or two
        let h = |t: &str| head(t).unwrap().unwrap().refusal(lo);
        assert_eq!(
            h("GET / HTTP/1.0\r\n\r\n"),
            Some((421, "Misdirected Request"))
        );
        assert_eq!(
            h("GET / HTTP/1.1\r\nHost: localhost:8080\r\nHost: evil:8080\r\n\r\n"),
            Some((421, "Misdirected Request"))
        );
        assert_eq!(h("GET / HTTP/1.1\r\nHost: localhost:8080\r\n\r\n"), None);
    }

    /// A script of reads: bytes, or a timeout.
    struct Script(Vec<Option<&'static [u8]>>);

    impl Read for Script {
        fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
            if self.0.is_empty() {
                return Ok(0);
            }
            match self.0.remove(0) {
                Some(b) => {
                    let n = b.len().min(buf.len());
                    buf[..n].copy_from_slice(&b[..n]);
                    if n < b.len() {
                        self.0.insert(0, Some(&b[n..]));
                    }
                    Ok(n)
                }
                None => Err(ErrorKind::WouldBlock.into()),
            }
        }
    }

    impl ReadTimeout for Script {
        fn set_timeout(&mut self, _: Duration) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn the_head_is_read_in_pieces_up_to_its_limit() {
        let t = Duration::from_secs(5);
        let mut s = Script(vec![
            Some(b"GET / HT"),
            Some(b"TP/1.1\r\nHost: a\r\n"),
            Some(b"\r\nbody never read"),
        ]);
        assert_eq!(read_head(&mut s, t).unwrap().path, "/");
        assert_eq!(
            read_head(&mut Script(vec![Some(b"GET / HTTP/1.1\r\n"), None]), t),
            Err(Failure::Timeout)
        );
        assert_eq!(
            read_head(&mut Script(vec![Some(b"GET / HTTP/1.1\r\n")]), t),
            Err(Failure::Gone)
        );
        assert_eq!(read_head(&mut Script(vec![None]), t), Err(Failure::Gone));
        let long: &'static [u8] = Box::leak(
            format!("GET / HTTP/1.1\r\nX: {}\r\n\r\n", "y".repeat(MAX_HEAD))
                .into_bytes()
                .into(),
        );
        assert_eq!(
            read_head(&mut Script(vec![Some(long)]), t),
            Err(Failure::TooLarge)
        );
        assert_eq!(
            read_head(&mut Script(vec![Some(b"GET / HTTP/2.0\r\n")]), t),
            Err(Failure::Version)
        );
    }
}
