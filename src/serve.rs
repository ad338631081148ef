//! `bikedyn serve`: the stability explorer (`wasm/explorer/`, issue 34) on
//! this machine's loopback interface.
//!
//! The page also works opened as a file; served, the browser fetches the
//! WebAssembly module itself (`bikedyn.wasm`, compiled while it downloads)
//! instead of decoding the base64 copy of `bikedyn-wasm.js`, and a
//! configuration shared as a link (the page state is in the URL) opens on
//! any machine that serves the page. Only files inside the explorer folder
//! are served, only to this machine (127.0.0.1), and only to `GET` and
//! `HEAD`: it is a viewer, not a web server. A browser that accepts gzip
//! gets the text files and the module compressed (the module, 7.1 MB, in
//! about 1.6 MB; compressed once per version of a file).
//!
//! Not in the WebAssembly build (there is no socket to listen on there).

use std::collections::HashMap;
use std::io::{Read, Write};
use std::net::SocketAddr;
use std::path::{Component, Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::SystemTime;

/// Where the explorer is and which port to listen on.
#[derive(Clone, Debug)]
pub struct ServeOptions {
    /// The explorer folder (`index.html` and the module `bikedyn.wasm` that
    /// `bash wasm/build.sh` writes into it). Default: `wasm/explorer` of the
    /// clone, relative to the working folder.
    pub dir: PathBuf,
    /// TCP port on 127.0.0.1; 0 takes a free one. Default 8000.
    pub port: u16,
}

impl Default for ServeOptions {
    fn default() -> Self {
        ServeOptions {
            dir: PathBuf::from("wasm/explorer"),
            port: 8000,
        }
    }
}

/// Why the explorer cannot be served.
#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    /// The folder has no `index.html`.
    #[error("{dir}: no explorer page here (no index.html); the explorer is the folder wasm/explorer of a bikedyn clone, and --dir names it")]
    NoPage {
        /// The folder given.
        dir: String,
    },
    /// The module has not been built.
    #[error("{dir}: the WebAssembly module bikedyn.wasm is not built; `bash wasm/build.sh` builds it (about 5 min the first time; it adds the wasm32 target with rustup)")]
    NoModule {
        /// The folder given.
        dir: String,
    },
    /// The port is taken or not allowed.
    #[error("cannot listen on 127.0.0.1:{port}: {message} (--port chooses another; --port 0 takes a free one)")]
    Bind {
        /// The port asked for.
        port: u16,
        /// The system's message.
        message: String,
    },
    /// Reading the folder failed.
    #[error("{dir}: {message}")]
    Folder {
        /// The folder given.
        dir: String,
        /// The system's message.
        message: String,
    },
}

/// A listening explorer server.
pub struct Server {
    http: tiny_http::Server,
    root: PathBuf,
    address: SocketAddr,
    /// Each file's compressed body, for the version of it (modification
    /// time and length) it was compressed from.
    gzipped: Mutex<HashMap<PathBuf, (Option<SystemTime>, usize, Arc<Vec<u8>>)>>,
}

impl Server {
    /// Check the folder and listen (nothing is served until [`Server::run`]).
    pub fn bind(opts: &ServeOptions) -> Result<Server, ServeError> {
        let dir = opts.dir.display().to_string();
        if !opts.dir.join("index.html").is_file() {
            return Err(ServeError::NoPage { dir });
        }
        if !opts.dir.join("bikedyn.wasm").is_file() {
            return Err(ServeError::NoModule { dir });
        }
        let root = opts.dir.canonicalize().map_err(|e| ServeError::Folder {
            dir: dir.clone(),
            message: e.to_string(),
        })?;
        let http = tiny_http::Server::http(("127.0.0.1", opts.port)).map_err(|e| ServeError::Bind {
            port: opts.port,
            message: e.to_string(),
        })?;
        let address = http
            .server_addr()
            .to_ip()
            .unwrap_or_else(|| SocketAddr::from(([127, 0, 0, 1], opts.port)));
        Ok(Server {
            http,
            root,
            address,
            gzipped: Mutex::new(HashMap::new()),
        })
    }

    /// The page's address, e.g. `http://127.0.0.1:8000/`.
    pub fn url(&self) -> String {
        format!("http://{}/", self.address)
    }

    /// Serve until the process ends. `log` receives one line per request
    /// (method, path, status).
    pub fn run(&self, log: &dyn Fn(&str)) {
        for request in self.http.incoming_requests() {
            let method = request.method().clone();
            let url = request.url().to_string();
            let (status, body, kind, path) = respond(&self.root, &method, &url);
            let gzip = status == 200 && accepts_gzip(request.headers()) && compressible(kind);
            let body = match (&path, gzip) {
                (Some(path), true) => self.gzipped(path, body).to_vec(),
                _ => body,
            };
            log(&format!("{method} {url} {status}{}", if gzip { " (gzip)" } else { "" }));
            let head = method == tiny_http::Method::Head;
            let length = body.len();
            let mut response =
                tiny_http::Response::from_data(if head { Vec::new() } else { body }).with_status_code(status);
            for (name, value) in [
                ("Content-Type", kind),
                // A rebuilt module shows on the next reload.
                ("Cache-Control", "no-store"),
                ("X-Content-Type-Options", "nosniff"),
                ("Vary", "Accept-Encoding"),
            ]
            .into_iter()
            .chain(gzip.then_some(("Content-Encoding", "gzip")))
            {
                if let Ok(h) = tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()) {
                    response.add_header(h);
                }
            }
            if head {
                if let Ok(h) = tiny_http::Header::from_bytes(&b"Content-Length"[..], length.to_string().as_bytes()) {
                    response.add_header(h);
                }
            }
            // A browser that closed the connection is not an error of ours.
            let _ = request.respond(response);
        }
    }
}

impl Server {
    /// `body`, the file at `path`, gzip-compressed: from the cache while
    /// the file's modification time and length are those it was
    /// compressed from, else compressed now (the module takes about half a
    /// second) and kept. A compression that fails sends the file as it is.
    fn gzipped(&self, path: &Path, body: Vec<u8>) -> Arc<Vec<u8>> {
        let modified = std::fs::metadata(path).and_then(|m| m.modified()).ok();
        let mut cache = self.gzipped.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((m, n, z)) = cache.get(path) {
            if *m == modified && *n == body.len() && modified.is_some() {
                return Arc::clone(z);
            }
        }
        let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        match encoder.write_all(&body).and_then(|_| encoder.finish()) {
            Ok(z) => {
                let z = Arc::new(z);
                cache.insert(path.to_path_buf(), (modified, body.len(), Arc::clone(&z)));
                z
            }
            Err(_) => Arc::new(body),
        }
    }
}

/// Whether the request's `Accept-Encoding` accepts gzip (named, or `*`, with
/// a quality above zero).
fn accepts_gzip(headers: &[tiny_http::Header]) -> bool {
    headers
        .iter()
        .filter(|h| h.field.equiv("Accept-Encoding"))
        .flat_map(|h| h.value.as_str().split(','))
        .any(|coding| {
            let mut parts = coding.split(';').map(str::trim);
            let name = parts.next().unwrap_or("");
            let refused = parts.any(|p| {
                p.strip_prefix("q=")
                    .and_then(|q| q.trim().parse::<f64>().ok())
                    .is_some_and(|q| q <= 0.0)
            });
            (name.eq_ignore_ascii_case("gzip") || name == "*") && !refused
        })
}

/// Whether a file of this content type gains from compression (images
/// are compressed already).
fn compressible(kind: &str) -> bool {
    !kind.starts_with("image/png")
}

/// Status, body, content type and file of a request for `url` under `root`.
fn respond(root: &Path, method: &tiny_http::Method, url: &str) -> (u16, Vec<u8>, &'static str, Option<PathBuf>) {
    const TEXT: &str = "text/plain; charset=utf-8";
    if !matches!(method, tiny_http::Method::Get | tiny_http::Method::Head) {
        return (405, b"only GET and HEAD\n".to_vec(), TEXT, None);
    }
    let Some(path) = resolve(root, url) else {
        return (404, format!("not found: {url}\n").into_bytes(), TEXT, None);
    };
    let mut body = Vec::new();
    match std::fs::File::open(&path).and_then(|mut f| f.read_to_end(&mut body)) {
        Ok(_) => {
            let kind = content_type(&path);
            (200, body, kind, Some(path))
        }
        Err(_) => (404, format!("not found: {url}\n").into_bytes(), TEXT, None),
    }
}

/// The file a URL path names inside `root`, if it is one: the query and
/// fragment dropped, `%XX` decoded, `/` the page; no `..`, no hidden
/// names, and nothing a link leads out of the folder to.
fn resolve(root: &Path, url: &str) -> Option<PathBuf> {
    let path = url.split(['?', '#']).next().unwrap_or("");
    let decoded = percent_decode(path)?;
    let mut file = root.to_path_buf();
    let mut any = false;
    for part in decoded.split('/').filter(|p| !p.is_empty()) {
        let mut components = Path::new(part).components();
        match (components.next(), components.next()) {
            (Some(Component::Normal(name)), None) if !part.starts_with('.') && !part.contains('\\') => {
                file.push(name);
                any = true;
            }
            _ => return None,
        }
    }
    if !any {
        file.push("index.html");
    }
    let real = file.canonicalize().ok()?;
    (real.starts_with(root) && real.is_file()).then_some(real)
}

/// `%XX` decoding of a URL path (UTF-8), `None` if malformed.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// The content type by extension (`application/wasm` lets the browser
/// compile the module while it downloads).
fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()).unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "wasm" => "application/wasm",
        "json" => "application/json",
        "svg" => "image/svg+xml",
        "png" => "image/png",
        "toml" | "txt" | "csv" | "md" => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}
