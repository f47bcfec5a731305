#!/usr/bin/env python3
"""Checks the workspace's architecture: no cycles between source files, and crates depending only the allowed way.

The file graph: a file depends on another when it uses an item defined there. `use` trees and inline
`crate::` / `super::` / `self::` / `<crate>::` / child-module paths are resolved to the file that defines the named
item, through re-exports and imports; a `mod` declaration or a re-export alone is no dependency. An inherent
`impl` of a type away from the type's own file counts both ways (the type's users call its methods, the methods
use the type), so a type and its methods live in one file. `#[cfg(test)]` modules are left out: tests may use
anything. The analysis is textual (comments and strings are blanked first), which suits this workspace's style:
every item a file uses is imported or named by path.

Run: `python3 tools/architecture.py` (exit 1 on a cycle or a forbidden crate dependency; `--edges` lists the
graph; `--crate NAME=ROOT ...` checks other crates' files instead). `tests/tests/architecture.rs` runs it in the
test suite.
"""
import os, re, sys, json
from collections import defaultdict

def strip(src):
    out = []; i = 0; n = len(src)
    while i < n:
        c = src[i]
        if src.startswith('//', i):
            j = src.find('\n', i); j = n if j < 0 else j
            out.append(' ' * (j - i)); i = j; continue
        if src.startswith('/*', i):
            depth = 0; j = i
            while j < n:
                if src.startswith('/*', j): depth += 1; j += 2; continue
                if src.startswith('*/', j):
                    depth -= 1; j += 2
                    if depth == 0: break
                    continue
                j += 1
            out.append(re.sub(r'[^\n]', ' ', src[i:j])); i = j; continue
        m = re.match(r'b?r(#*)"', src[i:i+10])
        if m and (i == 0 or not (src[i-1].isalnum() or src[i-1] == '_')):
            hashes = m.group(1); end = '"' + hashes
            j = src.find(end, i + len(m.group(0)))
            j = n if j < 0 else j + len(end)
            out.append(re.sub(r'[^\n]', ' ', src[i:j])); i = j; continue
        if c == '"' :
            j = i + 1
            while j < n and src[j] != '"':
                j += 2 if src[j] == '\\' else 1
            j += 1
            out.append(re.sub(r'[^\n]', ' ', src[i:j])); i = j; continue
        if c == "'":
            m = re.match(r"'(\\.|\\x..|\\u\{[0-9a-fA-F]+\}|[^\\'])'", src[i:i+12])
            if m:
                out.append(' ' * len(m.group(0))); i += len(m.group(0)); continue
        out.append(c); i += 1
    return ''.join(out)

class Crate:
    def __init__(self, name, root):
        self.name = name; self.root = root  # root: lib.rs or main.rs path
        self.modfile = {}  # module path tuple -> file
        self.walk((), root)
    def walk(self, mp, f):
        self.modfile[mp] = f
        src = strip(open(f).read())
        d = os.path.dirname(f)
        base = os.path.basename(f)
        sub = d if base in ('mod.rs', 'lib.rs', 'main.rs') else os.path.join(d, base[:-3])
        for m in re.finditer(r'(?:#\[path\s*=\s*"([^"]+)"\]\s*)?(?:pub(?:\([^)]*\))?\s+)?mod\s+([a-z_0-9]+)\s*;', open(f).read()):
            name = m.group(2)
            if m.group(1):
                cand = [os.path.join(d, m.group(1))]
            else:
                cand = [os.path.join(sub, name + '.rs'), os.path.join(sub, name, 'mod.rs')]
            for c in cand:
                if os.path.exists(c):
                    self.walk(mp + (name,), c); break

ITEM_RE = re.compile(r'\b(?:pub(?:\([^)]*\))?\s+)?(?:unsafe\s+|async\s+|const\s+|extern\s+"C"\s+)*(struct|enum|trait|fn|type|const|static|union|macro_rules!)\s+([A-Za-z_][A-Za-z_0-9]*)')
USE_RE = re.compile(r'\b(pub(?:\([^)]*\))?\s+)?use\s+([^;]+);')

def analyse(crates):
    by_name = {c.name: c for c in crates}
    info = {}  # file -> dict(defs, reexports, uses, crate, mp)
    for c in crates:
        for mp, f in c.modfile.items():
            raw = open(f).read()
            # drop #[cfg(test)] mod tests { ... } blocks: tests may use anything
            src = strip(raw)
            src = drop_test_blocks(src)
            defs = set(m.group(2) for m in ITEM_RE.finditer(src))
            reexp = {}; uses = []; imports = {}
            for m in USE_RE.finditer(src):
                tree = re.sub(r'\s+as\s+', '\x00', m.group(2))
                tree = re.sub(r'\s+', '', tree)
                items = []
                expand(tree, [], items)
                for path, alias in items:
                    nm = alias or path[-1]
                    if m.group(1):
                        reexp[nm] = path
                    imports[nm] = path
                    uses.append(path)
            # inline paths
            for m in re.finditer(r'(?<![A-Za-z_0-9:])((?:crate|super|self|[a-z_][a-z_0-9]*)(?:::[A-Za-z_][A-Za-z_0-9]*)+)', src):
                p = m.group(1).split('::')
                uses.append(p)
            impls = [m.group(1) for m in re.finditer(r'\bimpl\s*(?:<[^{>]*>)?\s*([A-Z][A-Za-z0-9_]*)\s*(?:<[^{]*>)?\s*\{', src)]
            info[f] = dict(defs=defs, reexp=reexp, uses=uses, crate=c, mp=mp, impls=impls, imports=imports)
    return info

def drop_test_blocks(src):
    out = src
    while True:
        m = re.search(r'#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+[a-z_0-9]+\s*\{', out)
        if not m: return out
        i = m.end() - 1; depth = 0; j = i
        while j < len(out):
            if out[j] == '{': depth += 1
            elif out[j] == '}':
                depth -= 1
                if depth == 0: break
            j += 1
        out = out[:m.start()] + re.sub(r'[^\n]', ' ', out[m.start():j+1]) + out[j+1:]

def expand(t, prefix, res):
    if t.startswith('{') and t.endswith('}'):
        depth = 0; cur = ''
        for ch in t[1:-1]:
            if ch == '{': depth += 1
            if ch == '}': depth -= 1
            if ch == ',' and depth == 0:
                if cur: expand(cur, prefix, res)
                cur = ''
            else: cur += ch
        if cur: expand(cur, prefix, res)
        return
    i = t.find('::{')
    if i >= 0 and t.endswith('}'):
        expand(t[i+2:], prefix + t[:i].split('::'), res); return
    alias = None
    if '\x00' in t:
        t, alias = t.split('\x00')
    res.append((prefix + t.split('::'), alias))

def resolve(info, crates_by_name, crate, mp, path, depth=0):
    """Return the file defining the item named by `path` from module mp of crate, or None (external)."""
    if depth > 20: return None
    p = list(path)
    if not p: return None
    if p[0] == 'crate':
        cur = (); p = p[1:]
    elif p[0] == 'self':
        cur = mp; p = p[1:]
    elif p[0] == 'super':
        cur = mp
        while p and p[0] == 'super':
            cur = cur[:-1]; p = p[1:]
    elif p[0] in crates_by_name and p[0] != crate.name:
        crate = crates_by_name[p[0]]; cur = (); p = p[1:]
    elif (mp + (p[0],)) in crate.modfile:
        cur = mp
    else:
        return None
    while True:
        f = crate.modfile[cur]
        if not p: return f
        nxt = cur + (p[0],)
        if nxt in crate.modfile:
            cur = nxt; p = p[1:]; continue
        fi = info[f]
        if p[0] in fi['defs']:
            return f
        if p[0] in fi['imports'] and p[0] != 'self':
            tgt = fi['imports'][p[0]]
            r = resolve(info, crates_by_name, crate, cur, tgt + p[1:], depth + 1)
            return r
        if p[0] == '*':
            return None
        # glob re-exports
        for nm, tgt in fi['reexp'].items():
            pass
        return f  # unknown name in module (enum variant, method, glob); attribute to the module file

# The workspace's crates: name in code -> crate root. A crate added to the workspace is added here.
CRATES = {
    "drivers": "drivers/src/lib.rs",
    "scene": "tracker/scene/src/lib.rs",
    "tracker": "tracker/core/src/lib.rs",
    "eval": "tracker/eval/src/lib.rs",
    "eventtrack6d": "tracker/app/src/lib.rs",
    "eventtrack6d_bin": "tracker/app/src/bin/eventtrack6d/main.rs",
    "hil_sim": "hil-sim/src/lib.rs",
    "hil_sim_bin": "hil-sim/src/main.rs",
    "firmware_trigger": "firmware-trigger/src/lib.rs",
    "eventtrack6d_tests": "tests/src/lib.rs",
    "cli_reference": "tools/cli-reference/src/lib.rs",
    "usbip": "usbip/src/lib.rs",
    "ros2": "ros2/src/lib.rs",
}

# Which of the workspace's packages each package may depend on (normal dependencies; DESIGN.md section 2,
# docs/architecture.md): drivers <- scene <- core <- eval, app; hil-sim <- drivers, scene, usbip, ros2; app <- ros2;
# tests may use all.
ALLOWED = {
    "eventtrack6d-drivers": set(),
    "eventtrack6d-scene": set(),
    "eventtrack6d-core": {"drivers", "scene"},
    "eventtrack6d-eval": {"drivers", "scene", "tracker"},
    "eventtrack6d": {"drivers", "scene", "tracker", "eval", "cli-reference", "ros2"},
    "hil-sim": {"drivers", "scene", "cli-reference", "usbip", "ros2"},
    "firmware-trigger": set(),
    "eventtrack6d-tests": None,  # anything
    "cli-reference": set(),
    "eventtrack6d-usbip": set(),
    "eventtrack6d-ros2": set(),
}
MANIFESTS = {
    "eventtrack6d-drivers": "drivers/Cargo.toml",
    "eventtrack6d-scene": "tracker/scene/Cargo.toml",
    "eventtrack6d-core": "tracker/core/Cargo.toml",
    "eventtrack6d-eval": "tracker/eval/Cargo.toml",
    "eventtrack6d": "tracker/app/Cargo.toml",
    "hil-sim": "hil-sim/Cargo.toml",
    "firmware-trigger": "firmware-trigger/Cargo.toml",
    "eventtrack6d-tests": "tests/Cargo.toml",
    "cli-reference": "tools/cli-reference/Cargo.toml",
    "eventtrack6d-usbip": "usbip/Cargo.toml",
    "eventtrack6d-ros2": "ros2/Cargo.toml",
}
OURS = {"drivers", "scene", "tracker", "eval", "eventtrack6d", "hil-sim", "firmware-trigger", "cli-reference", "usbip", "ros2"}


def crate_violations():
    """Workspace dependencies a package's [dependencies] table names beyond what ALLOWED lets it use."""
    problems = []
    for package, manifest in MANIFESTS.items():
        text = open(manifest).read()
        m = re.search(r'^\[dependencies\]\n(.*?)(?=^\[|\Z)', text, re.M | re.S)
        deps = set()
        if m:
            for line in m.group(1).splitlines():
                k = re.match(r'\s*([A-Za-z0-9_-]+)\s*(=|\.)', line)
                if k and k.group(1) in OURS:
                    deps.add(k.group(1))
        allowed = ALLOWED[package]
        if allowed is not None:
            for d in sorted(deps - allowed):
                problems.append(f"{package} depends on {d}, which it may not ({manifest})")
    return problems


def file_graph(crates):
    """Edges file -> files whose items it uses, and the inherent impls found away from their type's file."""
    by_name = {c.name: c for c in crates}
    info = analyse(crates)
    edges = defaultdict(set)
    for f, fi in info.items():
        reexports = [tuple(v) for v in fi['reexp'].values()]
        for u in fi['uses']:
            if tuple(u) in reexports:
                continue  # a re-export names an item; it uses nothing
            t = resolve(info, by_name, fi['crate'], fi['mp'], u)
            if t and t != f:
                edges[f].add(t)
    # An inherent impl of a type defined in another file: the type's file depends on it (its users call those
    # methods through the type), and it depends on the type's file.
    scattered = []
    for f, fi in info.items():
        for ty in fi['impls']:
            if ty in fi['defs']:
                continue
            owner = None
            for u in fi['uses']:
                if u[-1] == ty:
                    owner = resolve(info, by_name, fi['crate'], fi['mp'], u)
            if owner is None:
                for u in fi['uses']:
                    if u[-1] == '*':
                        mod = resolve(info, by_name, fi['crate'], fi['mp'], u[:-1])
                        if mod and ty in info[mod]['defs']:
                            owner = mod
            if owner and owner != f:
                edges[owner].add(f)
                edges[f].add(owner)
                scattered.append((ty, f, owner))
    return info, edges, scattered


def cycles(nodes, edges):
    """Strongly connected components of more than one file (Tarjan)."""
    idx, low, stack, on, out, counter = {}, {}, [], set(), [], [0]
    sys.setrecursionlimit(100000)

    def visit(v):
        idx[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
            if w not in idx:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], idx[w])
        if low[v] == idx[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(comp)

    for v in nodes:
        if v not in idx:
            visit(v)
    return out


def main():
    # `--crate NAME=ROOT` (repeatable) checks only those crates' files, and no manifests.
    given = [a.split('=', 1) for a in sys.argv[1:] if '=' in a]
    if given:
        crates = [Crate(n, r) for n, r in given]
        problems = []
    else:
        os.chdir(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
        crates = [Crate(n, r) for n, r in CRATES.items()]
        problems = crate_violations()
    info, edges, scattered = file_graph(crates)
    found = cycles(list(info), edges)
    print(f"files: {len(info)}, dependencies between files: {sum(len(v) for v in edges.values())}, "
          f"cycles: {len(found)}, crate direction violations: {len(problems)}")
    for ty, f, owner in scattered:
        print(f"  impl {ty} in {f}, away from its type's file {owner}")
    for c in sorted(found, key=len, reverse=True):
        print(f"  cycle of {len(c)} files:")
        for f in sorted(c):
            outs = sorted(set(edges[f]) & set(c))
            print(f"    {f} -> {', '.join(outs)}")
    for p in problems:
        print(f"  {p}")
    if '--edges' in sys.argv:
        for f in sorted(edges):
            print(f, '->', ' '.join(sorted(edges[f])))
    sys.exit(1 if found or problems else 0)


main()
