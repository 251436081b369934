"""The shape of the code: small modules and functions (issue 12's house rules)."""

import ast
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src" / "visemeface"
#: Modules allowed over the limit, with the reason (kept in the module's docstring too).
LONG_MODULES = {
    "physics/tled.py": "the numba kernels are unrolled straight-line code (see its docstring)",
}
#: Functions allowed over the limit, with the reason.
LONG_FUNCTIONS = {
    "physics/tled.py:_element_force": "one element's forces as straight-line scalar code for numba: "
                                      "no temporaries in the parallel loop (50-100x slower with them)",
}
MAX_MODULE_LINES = 500
MAX_FUNCTION_LINES = 100


def _modules():
    return sorted(p for p in SRC.rglob("*.py"))


@pytest.mark.parametrize("path", _modules(), ids=lambda p: str(p.relative_to(SRC)))
def test_modules_and_functions_are_small(path):
    rel = str(path.relative_to(SRC))
    text = path.read_text()
    if rel not in LONG_MODULES:
        assert text.count("\n") <= MAX_MODULE_LINES, f"{rel}: {text.count(chr(10))} lines"
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            n = node.end_lineno - node.lineno + 1
            if f"{rel}:{node.name}" in LONG_FUNCTIONS:
                continue
            assert n <= MAX_FUNCTION_LINES, f"{rel}:{node.lineno} {node.name}() has {n} lines"


def _import_graph() -> dict[str, set[str]]:
    """Module -> the package's modules it imports, at the top or inside functions (a module's own enclosing
    packages are no edge: Python imports them first whatever the module does)."""
    root = SRC.parent
    names = {}
    for p in _modules():
        parts = p.relative_to(root).with_suffix("").parts
        names[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = p
    graph = {m: set() for m in names}
    for m, p in names.items():
        package = m if p.name == "__init__.py" else m.rsplit(".", 1)[0]
        for node in ast.walk(ast.parse(p.read_text())):
            if isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    up = package.split(".")[:len(package.split(".")) - node.level + 1]
                    base = ".".join(up + ([node.module] if node.module else []))
                subs = [f"{base}.{a.name}" for a in node.names if f"{base}.{a.name}" in names]
                targets = subs if len(subs) == len(node.names) else [base, *subs]
            elif isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            else:
                continue
            graph[m] |= {t for t in targets if t in names and t != m and not m.startswith(t + ".")}
    return graph


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm, iteratively)."""
    index, low, on, stack, out, counter = {}, {}, set(), [], [], [0]
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, children = work[-1]
            w = next(children, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))
    return out


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle_counting_imports_inside_functions():
    """Two modules importing each other (one of them inside a function) are one idea in two homes."""
    graph = _import_graph()
    assert len(graph) > 100 and "visemeface.speech.tokens" in graph["visemeface.speech.g2p"]   # a live graph
    assert _cycles(graph) == []


#: Library modules that import the command line, with the reason (to be moved, not added to).
REACHING_THE_COMMANDS = {
    "visemeface.api": "its calls run the commands' own parsers, so that a call and a command share their defaults",
    "visemeface.__main__": "the program's entry point",
}


def test_the_library_never_imports_the_command_line_but_where_listed():
    """The commands (``cli``, ``commands.*``) are argparse around the library; the library does not reach back."""
    graph = _import_graph()
    cli = {m for m in graph if m == "visemeface.cli" or m.startswith("visemeface.commands")}
    reaching = {m for m in graph if m not in cli and graph[m] & cli}
    assert reaching == set(REACHING_THE_COMMANDS), sorted(reaching)
