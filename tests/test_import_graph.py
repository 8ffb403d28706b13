"""drake_auv's imports run one way: from a higher layer down to a lower one.

Every import statement of the package counts, lazy ones inside functions included. Two graphs
must be acyclic: the file graph (node = one module) and the package graph (node =
`drake_auv.<package>` for a subpackage, `drake_auv.<module>` for a top-level module). A cycle
fails with the imports that close it, as `file:line -> module`.
"""

import ast
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "drake_auv"

def _modules(root):
    """Module name -> file, for every module of the package under `root`."""
    modules = {}
    for path in sorted((root / PACKAGE).rglob("*.py")):
        parts = path.relative_to(root).with_suffix("").parts
        modules[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return modules


def _resolve(name, modules):
    """The module `name` denotes: itself, or its longest prefix that is a module."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name


def _imports(module, path, modules):
    """(imported module, line) for every import statement of `module` into the package."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join(anchor + ([node.module] if node.module else []))
            # `from a import b` imports the module a.b when there is one, else a name of a.
            names = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in modules else base
                     for alias in node.names]
        else:
            continue
        for name in names:
            target = _resolve(name, modules) if name.startswith(PACKAGE) else ""
            if target and target != module:
                yield target, node.lineno


def _node(module):
    """The package-graph node of `module`: `drake_auv.<first-level package or module>`."""
    return ".".join(module.split(".")[:2])


def import_graphs(root=ROOT):
    """The file and package graphs, node -> {node: {"file:line -> module", ...}}."""
    modules = _modules(root)
    files = defaultdict(lambda: defaultdict(set))
    packages = defaultdict(lambda: defaultdict(set))
    for module, path in modules.items():
        for target, line in _imports(module, path, modules):
            where = f"{path.relative_to(root)}:{line} -> {target}"
            files[module][target].add(where)
            if _node(module) != _node(target):
                packages[_node(module)][_node(target)].add(where)
    return files, packages


def cycles(graph):
    """The strongly connected components of more than one node (Tarjan), each with the imports
    inside it."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node):
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for w in graph.get(node, ()):
            if w not in index:
                visit(w)
                low[node] = min(low[node], low[w])
            elif w in on_stack:
                low[node] = min(low[node], index[w])
        if low[node] == index[node]:
            component = {stack.pop()}
            while node not in component:
                component.add(stack.pop())
            on_stack.difference_update(component)
            if len(component) > 1:
                found.append(sorted(where for v in component for w in graph.get(v, ())
                                    if w in component for where in graph[v][w]))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return found


def _report(found):
    return "\n\n".join("\n".join(imports) for imports in found)


def test_no_file_imports_itself_through_others():
    files, _ = import_graphs()
    found = cycles(files)
    assert not found, f"import cycles between files:\n{_report(found)}"


def test_no_package_imports_itself_through_others():
    _, packages = import_graphs()
    found = cycles(packages)
    assert not found, f"import cycles between packages:\n{_report(found)}"


def test_a_cycle_is_found_and_named():
    graph = {"a": {"b": ["a.py:1 -> b"]}, "b": {"c": ["b.py:2 -> c"]},
             "c": {"a": ["c.py:3 -> a"]}, "d": {"a": ["d.py:4 -> a"]}}
    assert cycles(graph) == [["a.py:1 -> b", "b.py:2 -> c", "c.py:3 -> a"]]
    del graph["b"]["c"]
    assert cycles(graph) == []
