//! `bikedyn serve`: the explorer folder on 127.0.0.1, files with the types
//! a browser needs, nothing outside the folder, and clear errors for a
//! folder that is not the explorer or a module that is not built. (The
//! page itself is driven in Chromium over `bikedyn serve` by
//! `wasm/tests/explorer.sh`.)

use crate::common::{bikedyn, scratch, text};
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Child, Command, Stdio};

/// A stand-in explorer folder (the real module is built apart, by
/// `wasm/build.sh`, after these tests in CI), with a secret beside it.
fn explorer(name: &str, module: bool) -> std::path::PathBuf {
    let root = scratch("serve").join(name);
    let _ = std::fs::remove_dir_all(&root);
    let dir = root.join("explorer");
    std::fs::create_dir_all(dir.join("sub dir")).unwrap();
    std::fs::write(dir.join("index.html"), "<!doctype html><title>explorer</title>\n").unwrap();
    std::fs::write(dir.join("plot.js"), "var x = 1;\n").unwrap();
    std::fs::write(dir.join("sub dir").join("a b.css"), "body {}\n").unwrap();
    std::fs::write(dir.join(".hidden"), "no\n").unwrap();
    std::fs::write(root.join("secret.txt"), "not for the browser\n").unwrap();
    if module {
        std::fs::write(dir.join("bikedyn.wasm"), b"\0asm\x01\0\0\0").unwrap();
    }
    dir
}

struct Serving {
    child: Child,
    port: u16,
}

impl Drop for Serving {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// `bikedyn serve --port 0` on `dir`; the port from the address it prints.
fn serve(dir: &std::path::Path) -> Serving {
    let mut child = Command::new(env!("CARGO_BIN_EXE_bikedyn"))
        .args(["serve", "--port", "0", "--dir", dir.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let port = line
        .split("http://127.0.0.1:")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .and_then(|p| p.parse().ok())
        .unwrap_or_else(|| panic!("no address in {line:?}"));
    Serving { child, port }
}

/// Status, headers (lower case) and body of one request.
fn request(port: u16, method: &str, path: &str) -> (u16, String, Vec<u8>) {
    request_with(port, method, path, "")
}

/// [`request`] with more header lines (each ending in `\r\n`).
fn request_with(port: u16, method: &str, path: &str, headers: &str) -> (u16, String, Vec<u8>) {
    let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
    write!(
        s,
        "{method} {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n{headers}Connection: close\r\n\r\n"
    )
    .unwrap();
    let mut raw = Vec::new();
    s.read_to_end(&mut raw).unwrap();
    let split = raw.windows(4).position(|w| w == b"\r\n\r\n").expect("a header");
    let head = String::from_utf8_lossy(&raw[..split]).to_lowercase();
    let status = head.split_whitespace().nth(1).and_then(|c| c.parse().ok()).unwrap();
    let body = &raw[split + 4..];
    let body = if head.contains("transfer-encoding: chunked") {
        dechunk(body)
    } else {
        body.to_vec()
    };
    (status, head, body)
}

/// A chunked HTTP/1.1 body's bytes (a large file comes so).
fn dechunk(mut raw: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let line = raw.windows(2).position(|w| w == b"\r\n").expect("a chunk size");
        let size = usize::from_str_radix(text(&raw[..line]).split(';').next().unwrap().trim(), 16).unwrap();
        if size == 0 {
            return out;
        }
        out.extend_from_slice(&raw[line + 2..line + 2 + size]);
        raw = &raw[line + 2 + size + 2..];
    }
}

#[test]
fn serve_gives_the_explorer_files_with_their_types_and_nothing_else() {
    let dir = explorer("files", true);
    let server = serve(&dir);
    let (status, head, body) = request(server.port, "GET", "/");
    assert_eq!(status, 200, "{head}");
    assert!(head.contains("content-type: text/html"), "{head}");
    assert!(text(&body).contains("<title>explorer</title>"));
    // The module with the type that lets the browser compile it as it
    // downloads; a query (the page state) and escapes are understood.
    let (status, head, body) = request(server.port, "GET", "/bikedyn.wasm?v=2");
    assert_eq!(status, 200, "{head}");
    assert!(head.contains("content-type: application/wasm"), "{head}");
    assert_eq!(body, b"\0asm\x01\0\0\0");
    let (status, head, _) = request(server.port, "GET", "/sub%20dir/a%20b.css");
    assert!(status == 200 && head.contains("content-type: text/css"), "{head}");
    let (status, head, body) = request(server.port, "HEAD", "/plot.js");
    assert!(
        status == 200 && head.contains("text/javascript") && body.is_empty(),
        "{head}"
    );
    // Nothing outside the folder, no hidden file, no other method.
    for path in [
        "/../secret.txt",
        "/%2e%2e/secret.txt",
        "/sub%20dir/../../secret.txt",
        "/.hidden",
        "/missing.js",
    ] {
        let (status, _, body) = request(server.port, "GET", path);
        assert_eq!(status, 404, "{path}");
        assert!(!text(&body).contains("not for the browser"), "{path}");
    }
    let (status, _, _) = request(server.port, "POST", "/index.html");
    assert_eq!(status, 405);
}

#[test]
fn serve_compresses_for_a_browser_that_accepts_gzip() {
    let dir = explorer("gzip", true);
    // A module of a realistic size and make (repetitive, like code).
    let module: Vec<u8> = (0..400_000u32).flat_map(|k| (k % 251).to_le_bytes()).collect();
    std::fs::write(dir.join("bikedyn.wasm"), &module).unwrap();
    let server = serve(&dir);
    let gunzip = |z: &[u8]| {
        let mut out = Vec::new();
        flate2::read::GzDecoder::new(z).read_to_end(&mut out).unwrap();
        out
    };
    // Twice: compressed, then from the cache, the same bytes.
    let mut first = None;
    for _ in 0..2 {
        let (status, head, body) = request_with(
            server.port,
            "GET",
            "/bikedyn.wasm",
            "Accept-Encoding: gzip, deflate, br\r\n",
        );
        assert_eq!(status, 200, "{head}");
        assert!(
            head.contains("content-encoding: gzip") && head.contains("content-type: application/wasm"),
            "{head}"
        );
        assert!(
            body.len() < module.len() / 4,
            "{} bytes for {}",
            body.len(),
            module.len()
        );
        assert_eq!(gunzip(&body), module);
        assert!(first.as_ref().is_none_or(|f| *f == body));
        first = Some(body);
    }
    // A changed file is compressed again.
    std::fs::write(dir.join("plot.js"), "var y = 2;\n").unwrap();
    let (_, head, body) = request_with(server.port, "GET", "/plot.js", "Accept-Encoding: gzip\r\n");
    assert!(head.contains("content-encoding: gzip"), "{head}");
    assert_eq!(gunzip(&body), b"var y = 2;\n");
    // Not to a client that does not ask, or refuses it.
    for headers in ["", "Accept-Encoding: identity\r\n", "Accept-Encoding: gzip;q=0\r\n"] {
        let (status, head, body) = request_with(server.port, "GET", "/bikedyn.wasm", headers);
        assert!(
            status == 200 && !head.contains("content-encoding"),
            "{headers:?}: {head}"
        );
        assert_eq!(body, module, "{headers:?}");
    }
}

#[test]
fn serve_without_a_built_module_or_page_says_what_to_do() {
    let dir = explorer("unbuilt", false);
    let out = bikedyn(&["serve", "--port", "0", "--dir", dir.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("bikedyn.wasm") && err.contains("bash wasm/build.sh"),
        "{err}"
    );
    let parent = dir.parent().unwrap();
    let out = bikedyn(&["serve", "--port", "0", "--dir", parent.to_str().unwrap()]);
    let err = text(&out.stderr);
    assert!(err.contains("no index.html") && err.contains("--dir"), "{err}");
    // A port that is taken is named.
    let dir = explorer("taken", true);
    let first = serve(&dir);
    let out = bikedyn(&[
        "serve",
        "--port",
        &first.port.to_string(),
        "--dir",
        dir.to_str().unwrap(),
    ]);
    let err = text(&out.stderr);
    assert!(
        err.contains(&format!("127.0.0.1:{}", first.port)) && err.contains("--port"),
        "{err}"
    );
}
