#!/usr/bin/env python3
"""Check that no crate of the workspace has a module cycle.

Usage (from anywhere in the clone):

    python3 scripts/check_module_cycles.py            # every crate; exit 1 on a cycle
    python3 scripts/check_module_cycles.py --graph    # also print each module's uses
    python3 scripts/check_module_cycles.py --self-test  # on made-up crates with known cycles

What counts as a cycle. Modules that share a parent are siblings; a module
*uses* a sibling when its code, or the code of any module below it, names
a path into that sibling (`use crate::a::b`, `super::b::f()`, `self::..`,
or a `use` relative to the module's own children). Edges between a module
and its own ancestors or descendants do not count: a parent that declares
and re-exports its children, and a child that uses its parent's items, are
how Rust modules are meant to nest. A cycle is a set of siblings that reach
each other through such uses (a strongly connected component of more than
one). Each is printed with one use (file and line) for each edge, so the
cycle can be broken where it is weakest.

Across crates, cargo refuses a cycle itself, so this checks each crate's
own module tree: the library and binary roots of the workspace's crates,
following `mod` declarations (and `#[path]`) from each root. Comments,
doc comments and string literals are ignored: a documentation link is not a
dependency. Unit-test modules (`#[cfg(test)] mod ..`) are left out: a
test may build its input from anywhere in the crate without the crate's
own modules depending on each other. `$crate` paths in macros are skipped (they name the crate that
defines the macro, wherever it is expanded).

This is a text scan, not a compiler. A path is attributed to the deepest
module it names (`crate::a::b::Item` -> `a::b`), and through a re-export
to the module the item comes from (`super::cross_validate`, where the
parent has `pub use cross_validation::cross_validate`, is a use of
`cross_validation`; a `use x::*` glob is followed for the names `x`
defines or imports). What it cannot see: a name used unqualified after a
glob import (`use super::*;` then `quartic_roots(..)`) counts only as a use
of the glob's module, and items made by macros are not indexed.
"""
from __future__ import annotations

import argparse
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# The crate roots the workspace builds (library and binaries). The generated
# models are included by the application crate through `#[path]`.
CRATE_ROOTS = [
    ("bikedyn (library)", "src/lib.rs"),
    ("bikedyn (binary)", "src/main.rs"),
    ("bikedyn-runtime", "runtime/src/lib.rs"),
    ("bikedyn-report", "report/src/lib.rs"),
    ("bikedyn-modeler", "modeler/src/lib.rs"),
    ("bikedyn-wasm", "wasm/src/lib.rs"),
    ("bikedyn-python", "python/src/lib.rs"),
]

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"


def strip_comments_and_strings(text: str) -> str:
    """Blank out comments and string/char literals, keeping line numbers."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            depth, j = 1, i + 2
            while j < n and depth:
                if text.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif text.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == "r" and re.match(r'r#*"', text[i:i + 10]) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            hashes = re.match(r'r(#*)"', text[i:]).group(1)
            end = text.find('"' + hashes, i + 2 + len(hashes))
            end = n if end < 0 else end + 1 + len(hashes)
            out.append(re.sub(r"[^\n]", " ", text[i:end]))
            i = end
        elif c == '"':
            j = i + 1
            while j < n and text[j] != '"':
                j += 2 if text[j] == "\\" else 1
            out.append(re.sub(r"[^\n]", " ", text[i:j + 1]))
            i = j + 1
        elif c == "'":
            # a char literal ('a', '\n', '\u{..}'), not a lifetime ('a)
            m = re.match(r"'(\\u\{[0-9A-Fa-f]+\}|\\.|[^\\'])'", text[i:])
            if m:
                out.append(" " * len(m.group(0)))
                i += len(m.group(0))
            else:
                out.append(c)
                i += 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


class Module:
    def __init__(self, path: tuple[str, ...], file: str, body: str, line0: int, dir_for_children: str):
        self.path = path
        self.file = file
        self.body = body  # code with comments and strings blanked
        self.line0 = line0  # line of `body`'s first character in `file`
        self.children_dir = dir_for_children
        self.children: dict[str, Module] = {}


def matching_brace(text: str, open_at: int) -> int:
    depth = 0
    for j in range(open_at, len(text)):
        if text[j] == "{":
            depth += 1
        elif text[j] == "}":
            depth -= 1
            if depth == 0:
                return j
    return len(text) - 1


MOD_DECL = re.compile(r"((?:#\[[^\]]*\]\s*)*)(?:pub(?:\([^)]*\))?\s+)?mod\s+(" + IDENT + r")\s*([;{])")


def load_module(path: tuple[str, ...], file: str, body: str, line0: int, children_dir: str, raw: str, modules: dict) -> Module:
    m = Module(path, file, body, line0, children_dir)
    modules[path] = m
    # Child declarations at this module's own level (inline modules' bodies
    # are handled recursively, and blanked out of the parent's body so their
    # uses are theirs).
    own = list(body)
    pos = 0
    while True:
        d = MOD_DECL.search(body, pos)
        if not d:
            break
        attrs, name, kind = d.group(1), d.group(2), d.group(3)
        child_path = path + (name,)
        if re.search(r"cfg\(\s*test\s*\)", attrs):
            # unit tests: not part of the structure the crate ships
            end = matching_brace(body, d.end() - 1) if kind == "{" else d.end()
            for j in range(d.start(), end + 1 if kind == "{" else end):
                if own[j] != "\n":
                    own[j] = " "
            pos = end + 1 if kind == "{" else end
            continue
        if kind == "{":
            close = matching_brace(body, d.end() - 1)
            inner = body[d.end():close]
            inner_line0 = line0 + body.count("\n", 0, d.end())
            load_module(child_path, file, inner, inner_line0, os.path.join(children_dir, name), raw, modules)
            for j in range(d.end(), close):
                if own[j] != "\n":
                    own[j] = " "
            pos = close + 1
        else:
            pm = re.search(r'#\[path\s*=\s*"([^"]+)"\]', raw_attrs(raw, file, line0, body, d.start()))
            if pm:
                child_file = os.path.normpath(os.path.join(os.path.dirname(file) if not path or file.endswith(("mod.rs", "lib.rs", "main.rs")) else children_dir, pm.group(1)))
            else:
                a = os.path.join(children_dir, name + ".rs")
                b = os.path.join(children_dir, name, "mod.rs")
                child_file = a if os.path.isfile(a) else b
            if os.path.isfile(child_file):
                text = open(child_file, encoding="utf-8").read()
                stripped = strip_comments_and_strings(text)
                if child_file.endswith("mod.rs") or pm:
                    cdir = os.path.dirname(child_file) if child_file.endswith("mod.rs") else os.path.splitext(child_file)[0]
                else:
                    cdir = os.path.splitext(child_file)[0]
                load_module(child_path, child_file, stripped, 1, cdir, text, modules)
            pos = d.end()
    m.body = "".join(own)
    return m


def raw_attrs(raw: str, file: str, line0: int, body: str, at: int) -> str:
    """The attributes before a `mod` declaration, from the raw text (string
    literals are blanked in the stripped body, and `#[path]` is one)."""
    line = line0 + body.count("\n", 0, at)
    lines = open(file, encoding="utf-8").read().split("\n")
    out = []
    k = line - 1
    # the declaration's own line, and the attribute lines just above it
    out.append(lines[k] if k < len(lines) else "")
    k -= 1
    while k >= 0 and lines[k].strip().startswith("#["):
        out.append(lines[k])
        k -= 1
    return "\n".join(out)


def expand_use_tree(tree: str) -> list[str]:
    """`a::{b, c::{d, e}}` -> [`a::b`, `a::c::d`, `a::c::e`] (aliases and
    globs dropped to their module path)."""
    tree = re.sub(r"\s+as\s+" + IDENT, "", tree)  # aliases
    tree = re.sub(r"\s+", "", tree)
    out: list[str] = []

    def go(prefix: str, t: str):
        # split t at top-level commas
        parts, depth, cur = [], 0, ""
        for ch in t:
            if ch == "," and depth == 0:
                parts.append(cur)
                cur = ""
                continue
            depth += ch == "{"
            depth -= ch == "}"
            cur += ch
        if cur:
            parts.append(cur)
        for p in parts:
            if "{" in p:
                head, rest = p.split("{", 1)
                go(prefix + head, rest[:-1])
            else:
                out.append(prefix + p)

    go("", tree)
    return out


USE_STMT = re.compile(r"\buse\s+([^;]+);")
PATH_IN_CODE = re.compile(r"(?<![\w$])((?:crate|super|self)(?:\s*::\s*" + IDENT + r")+)")
ITEM_DEF = re.compile(r"^\s*(?:pub(?:\([^)]*\))?\s+)?(?:(?:const|async|unsafe|extern\s+\"C\")\s+)*"
                      r"(?:fn|struct|enum|const|static|type|trait|union|macro_rules!)\s+(" + IDENT + r")", re.M)


def index_module(m: Module) -> None:
    """The names a module defines, and the names its `use` statements
    bring in (a re-export `pub use a::b::Item` and a private import alike:
    both are reachable as `path::to::module::Item` from its descendants)."""
    m.items = set(ITEM_DEF.findall(m.body))
    m.imports = {}  # name -> the imported path's segments
    m.globs = []  # `use x::*` sources
    m.uses = []  # (segments, line) of every `use` leaf
    for u in USE_STMT.finditer(m.body):
        line = m.line0 + m.body.count("\n", 0, u.start())
        for p in expand_use_tree(u.group(1)):
            segs = [x for x in p.split("::") if x]
            if segs and segs[0] == "":
                segs = segs[1:]
            if not segs:
                continue
            if segs[-1] == "*":
                m.globs.append(segs[:-1])
                m.uses.append((segs[:-1], line))
                continue
            if segs[-1] == "self":  # `use a::b::{self, ..}`
                segs = segs[:-1]
            if segs:
                m.imports.setdefault(segs[-1], segs)
                m.uses.append((segs, line))


def resolve(mod: Module, segments: list[str], modules: dict, depth: int = 0) -> tuple[str, ...] | None:
    """The module a path names, seen from `mod`: the deepest module on the
    path, or, when the next segment is a name that module imports (a
    re-export), the module that name comes from."""
    if not segments or depth > 8:
        return None
    cur = list(mod.path)
    i = 0
    if segments[0] == "crate":
        cur, i = [], 1
    elif segments[0] in ("super", "self"):
        while i < len(segments) and segments[i] in ("super", "self"):
            if segments[i] == "super":
                if not cur:
                    return None
                cur = cur[:-1]
            i += 1
    elif tuple(cur + [segments[0]]) in modules:
        pass  # relative to the module's own children
    elif segments[0] in mod.imports and mod.imports[segments[0]] != segments:
        # a name brought in by a `use` of this module (`use super::fit;`
        # then `fit::Problem`)
        via = resolve(mod, mod.imports[segments[0]], modules, depth + 1)
        if via is None:
            return None
        return resolve(modules[via], ["self"] + segments[1:], modules, depth + 1) if via in modules else via
    else:
        return None  # another crate, the prelude, or an item in scope
    best = tuple(cur)
    for s in segments[i:]:
        nxt = best + (s,)
        if nxt in modules:
            best = nxt
            i += 1
        else:
            break
    # Follow a re-export: `super::cross_validate`, where the parent has
    # `pub use cross_validation::cross_validate`, names `cross_validation`.
    rest = segments[i:]
    if rest and best in modules:
        owner = modules[best]
        name = rest[0]
        if name not in owner.items and name in owner.imports:
            target = resolve(owner, owner.imports[name], modules, depth + 1)
            if target is not None:
                return target
        if name not in owner.items and name not in owner.imports:
            for g in owner.globs:
                src = resolve(owner, g, modules, depth + 1)
                if src is not None and src in modules and src != best:
                    sm = modules[src]
                    if name in sm.items or name in sm.imports:
                        return resolve(sm, ["self", name], modules, depth + 1) or src
    return best


def uses_of(mod: Module, modules: dict) -> list[tuple[tuple[str, ...], int]]:
    out = []
    body = mod.body
    for segs, line in mod.uses:
        t = resolve(mod, segs, modules)
        if t is not None:
            out.append((t, line))
    use_spans = [(u.start(), u.end()) for u in USE_STMT.finditer(body)]
    for p in PATH_IN_CODE.finditer(body):
        if any(a <= p.start() < b for a, b in use_spans):
            continue
        segs = [s.strip() for s in p.group(1).split("::")]
        t = resolve(mod, segs, modules)
        if t is not None:
            out.append((t, mod.line0 + body.count("\n", 0, p.start())))
    return out


def tarjan(nodes: list[str], edges: dict[str, set[str]]) -> list[list[str]]:
    index, low, on, stack, sccs = {}, {}, set(), [], []
    counter = [0]

    def strong(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(edges.get(v, ())):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            sccs.append(sorted(comp))

    for v in nodes:
        if v not in index:
            strong(v)
    return sccs


def check_crate(name: str, root_rel: str, show_graph: bool, base: str = ROOT) -> int:
    root = os.path.join(base, root_rel)
    if not os.path.isfile(root):
        print(f"{name}: no root at {root_rel}; skipped")
        return 0
    text = open(root, encoding="utf-8").read()
    modules: dict[tuple[str, ...], Module] = {}
    load_module((), root, strip_comments_and_strings(text), 1, os.path.dirname(root), text, modules)
    for m in modules.values():
        index_module(m)

    # sibling edges: parent -> {child -> {child: (file, line)}}
    sib: dict[tuple[str, ...], dict[str, dict[str, tuple[str, int]]]] = {}
    for m in modules.values():
        for target, line in uses_of(m, modules):
            a, b = m.path, target
            k = 0
            while k < min(len(a), len(b)) and a[k] == b[k]:
                k += 1
            if k == len(a) or k == len(b):
                continue  # ancestor or descendant
            parent = a[:k]
            sib.setdefault(parent, {}).setdefault(a[k], {}).setdefault(b[k], (os.path.relpath(m.file, base), line))

    cycles = 0
    for parent in sorted(sib):
        edges = {u: set(vs) for u, vs in sib[parent].items()}
        nodes = sorted(set(edges) | {v for vs in edges.values() for v in vs})
        pname = "::".join(("crate",) + parent)
        if show_graph:
            for u in nodes:
                if edges.get(u):
                    print(f"{name}: {pname}::{u} -> {', '.join(sorted(edges[u]))}")
        for comp in tarjan(nodes, edges):
            if len(comp) < 2:
                continue
            cycles += 1
            print(f"{name}: module cycle among {pname}::{{{', '.join(comp)}}}")
            for u in comp:
                for v in sorted(edges.get(u, ())):
                    if v in comp:
                        f, line = sib[parent][u][v]
                        print(f"    {u} -> {v}   ({f}:{line})")
    n = len(modules)
    print(f"{name}: {n} modules, {cycles} cycle(s)")
    return cycles


SELF_TEST = {
    # a direct cycle between siblings, and one through a parent's re-export
    "cyclic": ({
        "lib.rs": "mod a;\nmod b;\nmod p;\n",
        "a.rs": "use crate::b::X;\npub struct Y;\n",
        "b.rs": "pub struct X;\nfn f() -> crate::a::Y { todo!() }\n",
        "p/mod.rs": "mod q;\nmod r;\npub use q::Q;\n",
        "p/q.rs": "pub struct Q;\nfn g(_: super::r::R) {}\n",
        "p/r.rs": "use super::Q;\npub struct R;\n",
    }, 2),
    # what must not count: parent and child, unit tests, comments, strings,
    # documentation links, another crate's paths
    "acyclic": ({
        "lib.rs": "pub mod a;\npub mod b;\npub use a::A;\n",
        "a.rs": "use crate::b::B;\npub struct A(B);\n",
        "b.rs": "/// See [`crate::a::A`].\npub struct B;\n// crate::a::A\nconst S: &str = \"crate::a::A\";\n"
                "fn f() { let _ = super::b::B; let _ = other::a::A; }\n#[cfg(test)]\nmod tests {\n    use crate::a::A;\n}\n",
    }, 0),
}


def self_test() -> None:
    import tempfile
    failed = []
    for name, (files, want) in SELF_TEST.items():
        with tempfile.TemporaryDirectory() as d:
            for rel, text in files.items():
                os.makedirs(os.path.dirname(os.path.join(d, rel)), exist_ok=True)
                with open(os.path.join(d, rel), "w", encoding="utf-8") as fh:
                    fh.write(text)
            got = check_crate(f"self-test {name}", "lib.rs", False, base=d)
        if got != want:
            failed.append(f"{name}: {got} cycle(s) found, {want} expected")
    if failed:
        sys.exit("error: the checker's self-test failed: " + "; ".join(failed))
    print("self-test: every known cycle found, none invented")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--graph", action="store_true", help="print every sibling use, not only cycles")
    ap.add_argument("--self-test", action="store_true", help="check the checker on made-up crates first")
    args = ap.parse_args()
    if args.self_test:
        self_test()
    total = sum(check_crate(name, root, args.graph) for name, root in CRATE_ROOTS)
    if total:
        print(f"error: {total} module cycle(s); break each at one of the uses listed", file=sys.stderr)
        sys.exit(1)


if __name__ == "__main__":
    main()
