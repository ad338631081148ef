#!/usr/bin/env python3
"""Check the documentation: every relative link resolves, and every runnable
shell example runs.

Usage (from anywhere in the clone):

    python3 scripts/check_docs.py               # links, then examples
    python3 scripts/check_docs.py --links-only  # links only (no binary needed)
    python3 scripts/check_docs.py --list        # which blocks would run
    python3 scripts/check_docs.py README.md     # only the files named
    python3 scripts/check_docs.py --python .venv/bin/python   # the Python examples

Files: README.md, python/README.md and docs/*.md (links also in
examples/data/README.md).

Links: every Markdown link `[text](target)` that is not a URL must name an
existing file, relative to the page, and an `#anchor` must be a heading of
the page it points to (GitHub's anchor rules).

Examples: a fenced block opened with ```sh is runnable when its first line
that is not a comment starts with `bikedyn ` or `cargo run --release -- `.
A block is skipped when the line before its fence is an HTML comment
starting `<!-- no-check` (say why after it: a synopsis, data under
../shared, a long run). Runnable blocks of one page run in order, in one
scratch folder per page (so a block may use the files an earlier block of
the page wrote), with `bash -euo pipefail`; `cargo run --release --` is
replaced by the binary, and `bikedyn` is the binary on the PATH. The scratch
folder holds a copy of the clone's files (`examples/`, `tests/`, ...), so
paths in the clone work as written and no example changes the clone. A
block fails on a nonzero exit.

With `--python PY`, the ```python blocks run instead (each in the scratch
folder, as a file, with `PY` and MPLBACKEND=Agg), unless marked no-check;
a block that imports an optional module PY lacks (matplotlib, pandas, ...)
is skipped with a note.

The binary is `$BIKEDYN` when set, otherwise
`$CARGO_TARGET_DIR/release/bikedyn` when CARGO_TARGET_DIR is set, otherwise
`target/release/bikedyn`; build it first with
`cargo build --release --bin bikedyn`. Each block may take
`$CHECK_DOCS_TIMEOUT` seconds (default 600).
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import unicodedata

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Modules a Python example may use that the package does not need: a block
# importing one the interpreter lacks is skipped with a note.
OPTIONAL = {"matplotlib", "pandas", "bicycleparameters", "tqdm", "ray", "dask"}
RUNNABLE = re.compile(r"^(bikedyn|cargo run --release --)(\s|$)")
LINK = re.compile(r"(?<!!)\[(?:[^\[\]]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
IMAGE = re.compile(r"!\[[^\]]*\]\(([^)\s]+)\)")


def pages(args):
    if args:
        return [os.path.abspath(a) for a in args]
    docs = os.path.join(ROOT, "docs")
    out = [os.path.join(ROOT, "README.md"), os.path.join(ROOT, "python", "README.md")]
    if os.path.isdir(docs):
        out += sorted(
            os.path.join(docs, f) for f in os.listdir(docs) if f.endswith(".md")
        )
    return out


def rel(path):
    return os.path.relpath(path, ROOT)


def strip_code(lines):
    """The lines outside fenced code, with inline code removed (links in
    code are examples, not links)."""
    out, fenced = [], False
    for n, line in enumerate(lines, 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            out.append((n, re.sub(r"`[^`]*`", "", line)))
    return out


def anchor(heading):
    """GitHub's anchor of a heading's text."""
    text = re.sub(r"`", "", heading.strip()).lower()
    text = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", text)
    out = []
    for ch in text:
        if ch in " -":
            out.append("-")
        elif ch == "_" or ch.isalnum() or unicodedata.category(ch).startswith("L"):
            out.append(ch)
    return "".join(out)


def anchors(path, cache={}):
    if path not in cache:
        seen, found = {}, set()
        lines = open(path, encoding="utf-8").read().split("\n")
        fenced = False
        for line in lines:
            if line.lstrip().startswith("```"):
                fenced = not fenced
                continue
            m = re.match(r"^#{1,6}\s+(.*?)\s*#*\s*$", line)
            if m and not fenced:
                a = anchor(m.group(1))
                k = seen.get(a, 0)
                seen[a] = k + 1
                found.add(a if k == 0 else f"{a}-{k}")
        cache[path] = found
    return cache[path]


def check_links(files):
    errors = []
    for page in files:
        lines = open(page, encoding="utf-8").read().split("\n")
        for n, line in strip_code(lines):
            for m in list(LINK.finditer(line)) + list(IMAGE.finditer(line)):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):
                    continue  # a URL
                path, _, frag = target.partition("#")
                dest = (
                    page
                    if not path
                    else os.path.normpath(os.path.join(os.path.dirname(page), path))
                )
                if not os.path.exists(dest):
                    errors.append(f"{rel(page)}:{n}: link to missing file {target}")
                    continue
                if frag and dest.endswith(".md") and frag not in anchors(dest):
                    errors.append(
                        f"{rel(page)}:{n}: no heading for #{frag} in {rel(dest)}"
                    )
    return errors


def blocks(page):
    """(line, language, text, runnable, skip reason) of every ```sh and
    ```python block of a page."""
    lines = open(page, encoding="utf-8").read().split("\n")
    out, i = [], 0
    while i < len(lines):
        fence = lines[i].strip()
        if fence.startswith("```"):
            j = i + 1
            while j < len(lines) and not lines[j].strip().startswith("```"):
                j += 1
            lang = {"```sh": "sh", "```bash": "sh", "```shell": "sh", "```python": "python"}.get(fence)
            if lang:
                body = lines[i + 1 : j]
                first = next(
                    (l.strip() for l in body if l.strip() and not l.strip().startswith("#")),
                    "",
                )
                k = i - 1
                while k >= 0 and not lines[k].strip():
                    k -= 1
                skip = None
                if k >= 0 and lines[k].strip().startswith("<!-- no-check"):
                    skip = lines[k].strip()[len("<!-- no-check") :].strip(" :->") or "marked"
                runnable = lang == "python" or bool(RUNNABLE.match(first))
                out.append((i + 1, lang, "\n".join(body), runnable, skip))
            i = j + 1
        else:
            i += 1
    return out


def binary():
    if os.environ.get("BIKEDYN"):
        b = os.environ["BIKEDYN"]
    elif os.environ.get("CARGO_TARGET_DIR"):
        b = os.path.join(os.environ["CARGO_TARGET_DIR"], "release", "bikedyn")
    else:
        b = os.path.join(ROOT, "target", "release", "bikedyn")
    b = os.path.abspath(b)
    if not os.access(b, os.X_OK):
        sys.exit(
            f"check_docs: no bikedyn binary at {b}: build it with "
            "`cargo build --release --bin bikedyn`, or set BIKEDYN"
        )
    return b


def scratch(bin_path):
    """A scratch folder holding a copy of the clone's top-level entries (a
    few megabytes; a copy, so that no example can change the clone), with
    the binary on a PATH folder of its own."""
    work = tempfile.mkdtemp(prefix="bikedyn-docs-")
    for name in os.listdir(ROOT):
        if name.startswith(".") or name == "target":
            continue
        src, dst = os.path.join(ROOT, name), os.path.join(work, name)
        if os.path.isdir(src):
            shutil.copytree(src, dst, symlinks=True)
        else:
            shutil.copy2(src, dst)
    bindir = os.path.join(work, ".bin")
    os.mkdir(bindir)
    if bin_path:
        os.symlink(bin_path, os.path.join(bindir, "bikedyn"))
    return work, bindir


def missing_modules(python, body):
    """The optional modules a Python block imports that `python` lacks."""
    wanted = set(re.findall(r"^\s*(?:import|from)\s+(\w+)", body, re.M)) & OPTIONAL
    out = []
    for m in sorted(wanted):
        probe = f"import importlib.util, sys; sys.exit(importlib.util.find_spec({m!r}) is None)"
        if subprocess.run([python, "-c", probe]).returncode != 0:
            out.append(m)
    return out


def run_examples(files, listing, python=None):
    lang_run = "python" if python else "sh"
    bin_path = None if listing or python else binary()
    timeout = float(os.environ.get("CHECK_DOCS_TIMEOUT", "600"))
    failures, ran, skipped = [], 0, 0
    for page in files:
        todo = blocks(page)
        work = None
        for line, lang, body, runnable, skip in todo:
            where = f"{rel(page)}:{line}"
            if lang != lang_run:
                continue
            if python and runnable and not skip and not listing:
                lacking = missing_modules(python, body)
                if lacking:
                    skip = "no module " + ", ".join(lacking)
            if not runnable or skip:
                if runnable and skip:
                    skipped += 1
                    print(f"skip {where} ({skip})")
                continue
            if listing:
                print(f"run  {where}")
                continue
            if work is None:
                work, bindir = scratch(bin_path)
            env = dict(os.environ, PATH=bindir + os.pathsep + os.environ["PATH"])
            if python:
                with open(os.path.join(work, ".block.py"), "w", encoding="utf-8") as f:
                    f.write(body + "\n")
                command = [python, ".block.py"]
                env["MPLBACKEND"] = "Agg"
            else:
                script = re.sub(r"\bcargo run --release --(?=\s|$)", "bikedyn", body)
                command = ["bash", "-euo", "pipefail", "-c", script]
            start = time.time()
            try:
                p = subprocess.run(
                    command,
                    cwd=work,
                    env=env,
                    stdout=subprocess.PIPE,
                    stderr=subprocess.STDOUT,
                    timeout=timeout,
                )
                code, out = p.returncode, p.stdout.decode("utf-8", "replace")
            except subprocess.TimeoutExpired as e:
                code, out = "timeout", (e.stdout or b"").decode("utf-8", "replace")
            ran += 1
            took = time.time() - start
            if code == 0:
                print(f"ok   {where} ({took:.1f} s)")
            else:
                tail = "\n".join(out.rstrip().split("\n")[-15:])
                print(f"FAIL {where} (exit {code}, {took:.1f} s)\n{body}\n--- output (last lines)\n{tail}\n---")
                failures.append(where)
        if work is not None:
            shutil.rmtree(work, ignore_errors=True)
    if not listing:
        print(f"examples: {ran} run, {len(failures)} failed, {skipped} skipped by no-check")
    return failures


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="*", help="Markdown files (default: README.md, python/README.md, docs/*.md)")
    ap.add_argument("--links-only", action="store_true", help="check links only")
    ap.add_argument("--list", action="store_true", help="list the blocks that would run")
    ap.add_argument(
        "--python",
        metavar="PY",
        help="run the ```python blocks with this interpreter (bikedyn installed) instead of the shell blocks",
    )
    args = ap.parse_args()
    files = pages(args.files)
    extra = [] if args.files else [
        os.path.join(ROOT, p) for p in ("examples/data/README.md",)
        if os.path.exists(os.path.join(ROOT, p))
    ]
    errors = check_links(files + extra)
    for e in errors:
        print(e)
    print(f"links: {len(errors)} broken in {len(files + extra)} files")
    failures = [] if args.links_only else run_examples(files, args.list, args.python)
    sys.exit(1 if errors or failures else 0)


if __name__ == "__main__":
    main()
