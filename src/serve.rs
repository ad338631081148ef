//! `bikedyn serve`: the stability explorer (`wasm/explorer/`, issue 34) on
//! this machine's loopback interface.
//!
//! The page also works opened as a file; served, the browser fetches the
//! WebAssembly module itself (`bikedyn.wasm`, compiled while it downloads)
//! instead of decoding the base64 copy of `bikedyn-wasm.js`, and a
//! configuration shared as a link (the page state is in the URL) opens on
//! any machine that serves the page. Only files inside the explorer folder
//! are served, only to this machine (127.0.0.1), and only to `GET` and
//! `HEAD`: it is a viewer, not a web server.
//!
//! Not in the WebAssembly build (there is no socket to listen on there).

use std::io::Read;
use std::net::SocketAddr;
use std::path::{Component, Path, PathBuf};

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
        Ok(Server { http, root, address })
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
            let (status, body, kind) = respond(&self.root, &method, &url);
            log(&format!("{method} {url} {status}"));
            let head = method == tiny_http::Method::Head;
            let length = body.len();
            let mut response =
                tiny_http::Response::from_data(if head { Vec::new() } else { body }).with_status_code(status);
            for (name, value) in [
                ("Content-Type", kind),
                // A rebuilt module shows on the next reload.
                ("Cache-Control", "no-store"),
                ("X-Content-Type-Options", "nosniff"),
            ] {
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

/// Status, body and content type of a request for `url` under `root`.
fn respond(root: &Path, method: &tiny_http::Method, url: &str) -> (u16, Vec<u8>, &'static str) {
    const TEXT: &str = "text/plain; charset=utf-8";
    if !matches!(method, tiny_http::Method::Get | tiny_http::Method::Head) {
        return (405, b"only GET and HEAD\n".to_vec(), TEXT);
    }
    let Some(path) = resolve(root, url) else {
        return (404, format!("not found: {url}\n").into_bytes(), TEXT);
    };
    let mut body = Vec::new();
    match std::fs::File::open(&path).and_then(|mut f| f.read_to_end(&mut body)) {
        Ok(_) => (200, body, content_type(&path)),
        Err(_) => (404, format!("not found: {url}\n").into_bytes(), TEXT),
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
