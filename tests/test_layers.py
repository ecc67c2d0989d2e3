"""The package layering of ``avatar``, checked from the source (no imports are run).

Every module of ``src/avatar`` belongs to a *component*: the top-level package or module of
``avatar`` it lives in (``avatar.clothes.binder`` -> ``clothes``, ``avatar.errors`` -> ``errors``;
the package root ``avatar/__init__.py`` is the component ``avatar``). Each component has a rank
in LAYERS below, and:

- a module may import only components of the same or a lower rank (no upward import);
- the component graph has no cycle (not even between components of one rank);
- every module and every imported ``avatar`` component is placed in LAYERS, so a new package
  gets its rank deliberately.

Imports are read with ``ast``: module-level and function-level ``import x`` / ``from x import
y`` (``y`` resolved to a submodule where it is one) and relative imports. Imports under
``if TYPE_CHECKING:`` never run, so they are left out of both rules (they are still listed in
the printed graph, marked ``type-only``).

``pytest -s tests/test_layers.py`` prints the component graph with ranks.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path

import pytest

# The layer table, lowest first: rank -> components. A module may import its own rank and below.
# The single source of the layering: place every new top-level package or module of avatar here.
LAYERS: dict[int, tuple[str, ...]] = {
    0: ("errors", "mesh", "material", "part", "camera"),  # base records, errors, camera maths
    1: ("rig",),
    2: ("io",),  # file formats only
    3: ("body",),
    4: ("geometry",),  # closest points, winding numbers, k-d trees, shells, normals
    5: ("looks",),  # skin, eyes, fabrics, textures
    6: ("clothes", "motion"),
    7: ("human",),
    8: ("blender",),  # the bpy bridge; takes records
    9: ("export",),  # save/load front door: io writers + Blender writers
    # The command line and the Blender extension's engine are composition roots: they
    # realise recipes into Humans and write them (blender.character is the one module of
    # blender/ that does; the rest of the bridge takes records).
    10: ("cli", "blender.character", "dataset", "mocap"),
    11: ("avatar",),  # the package root avatar/__init__.py: the public API facade
}

ROOT = "avatar"
SRC = Path(__file__).resolve().parents[1] / "src" / ROOT
BLENDER_MODULES = ("bpy", "mathutils", "bmesh", "bpy_extras")

RANK: dict[str, int] = {comp: rank for rank, comps in LAYERS.items() for comp in comps}


@dataclass(frozen=True)
class Import:
    source: str  # importing module, e.g. avatar.clothes.binder
    target: str  # imported module, e.g. avatar.cli (or any other name: numpy, bpy)
    line: int
    type_only: bool  # under `if TYPE_CHECKING:`

    def __str__(self) -> str:
        return f"{self.source} -> {self.target} (line {self.line})"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def sources() -> list[tuple[str, Path]]:
    """Every source file of the package with its dotted module name (a name twice where a
    module and a package of one name both exist: test_no_shadowed_modules reports it)."""
    return [(module_name(p), p) for p in sorted(SRC.rglob("*.py"))]


def modules() -> set[str]:
    return {name for name, _ in sources()}


def component(name: str) -> str:
    """avatar.x.y -> x (or x.y where LAYERS places that module itself); avatar -> avatar."""
    parts = name.split(".")
    if len(parts) > 2 and ".".join(parts[1:3]) in RANK:
        return ".".join(parts[1:3])
    return parts[1] if len(parts) > 1 else parts[0]


def is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def read_imports(name: str, source: str, is_package: bool, known: set[str]) -> list[Import]:
    """All imports of module ``name`` (source text ``source``) at any depth: functions,
    classes, try/if blocks. ``known``: every module name, to tell submodules from names."""
    tree = ast.parse(source, filename=name)
    package = name if is_package else name.rpartition(".")[0]
    found: list[Import] = []

    def visit(node: ast.AST, type_only: bool) -> None:
        if isinstance(node, ast.Import):
            for alias in node.names:
                found.append(Import(name, alias.name, node.lineno, type_only))
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - (node.level - 1)]
                module = ".".join(base + ([node.module] if node.module else []))
            else:
                module = node.module or ""
            for alias in node.names:
                sub = f"{module}.{alias.name}"
                # `from avatar.x import y` imports the submodule avatar.x.y where there is one.
                found.append(Import(name, sub if sub in known else module, node.lineno, type_only))
        if isinstance(node, ast.If) and is_type_checking(node.test):
            for child in node.body:
                visit(child, True)
            for child in node.orelse:
                visit(child, type_only)
            return
        for child in ast.iter_child_nodes(node):
            visit(child, type_only)

    visit(tree, False)
    return list(dict.fromkeys(found))  # `from x import a, b`: one import per target and line


def all_imports() -> list[Import]:
    known = modules()
    return [
        imp
        for name, path in sources()
        for imp in read_imports(
            name, path.read_text(encoding="utf-8"), path.name == "__init__.py", known
        )
    ]


def internal(imports: list[Import]) -> list[Import]:
    """The imports of avatar modules by avatar modules."""
    return [i for i in imports if i.target == ROOT or i.target.startswith(ROOT + ".")]


def component_edges(imports: list[Import]) -> dict[tuple[str, str], list[Import]]:
    """(from component, to component) -> the imports making that edge (runtime ones only)."""
    edges: dict[tuple[str, str], list[Import]] = defaultdict(list)
    for imp in internal(imports):
        a, b = component(imp.source), component(imp.target)
        if a != b and not imp.type_only:
            edges[a, b].append(imp)
    return edges


def strongly_connected(nodes: set[str], edges: set[tuple[str, str]]) -> list[list[str]]:
    """Tarjan's strongly connected components (each sorted), of more than one node only."""
    succ: dict[str, list[str]] = defaultdict(list)
    for a, b in sorted(edges):
        succ[a].append(b)
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    out: list[list[str]] = []

    def connect(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in succ[v]:
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            scc = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                scc.append(w)
                if w == v:
                    break
            if len(scc) > 1:
                out.append(sorted(scc))

    for v in sorted(nodes):
        if v not in index:
            connect(v)
    return sorted(out)


def shortest_cycles(scc: list[str], edges: set[tuple[str, str]]) -> list[list[str]]:
    """For each member of a strongly connected component, the shortest cycle through it (breadth
    first), each written from its smallest component, without repeats. Every edge of the
    component lies on some cycle; these few are the ones to read first."""
    members = set(scc)
    succ: dict[str, list[str]] = defaultdict(list)
    for a, b in sorted(edges):
        if a in members and b in members:
            succ[a].append(b)
    cycles: list[list[str]] = []
    for start in scc:
        parent: dict[str, str] = {}
        frontier, end = [start], None
        while frontier and end is None:
            nxt = []
            for v in frontier:
                for w in succ[v]:
                    if w == start:
                        end = v
                        break
                    if w not in parent:
                        parent[w] = v
                        nxt.append(w)
                if end is not None:
                    break
            frontier = nxt
        assert end is not None, f"{start} is on no cycle of its own component"
        path = [end]
        while path[-1] != start:
            path.append(parent[path[-1]])
        path.reverse()  # start -> ... -> end (-> start)
        i = path.index(min(path))
        cycle = [*path[i:], *path[:i]]
        if cycle not in cycles:
            cycles.append(cycle)
    return sorted(cycles, key=lambda c: (len(c), c))


# ---------------------------------------------------------------------------------------------


def test_layer_table_is_consistent():
    comps = [c for cs in LAYERS.values() for c in cs]
    assert len(comps) == len(set(comps)), "a component is placed twice in LAYERS"
    assert sorted(LAYERS) == list(range(len(LAYERS)))


def test_no_shadowed_modules():
    """A module and a package of the same name: Python imports the package, the module is dead."""
    paths: dict[str, list[str]] = defaultdict(list)
    for name, path in sources():
        paths[name].append(str(path.relative_to(SRC.parent)))
    twice = [f"{name}: {' and '.join(p)}" for name, p in sorted(paths.items()) if len(p) > 1]
    assert not twice, "modules defined twice (the package wins):\n" + "\n".join(twice)


def test_every_component_is_placed():
    """Modules and imported avatar components not in LAYERS fail: place new packages on purpose."""
    problems = [
        f"{name}: unassigned component {component(name)!r} (add it to LAYERS)"
        for name in modules()
        if component(name) not in RANK
    ]
    problems += [
        f"{imp}: imports unassigned component {component(imp.target)!r}"
        for imp in internal(all_imports())
        if component(imp.target) not in RANK
    ]
    assert not problems, "unassigned components:\n" + "\n".join(problems)


def test_no_upward_imports():
    """A module imports only components of its own rank or below (TYPE_CHECKING ones exempt)."""
    violations = []
    for imp in internal(all_imports()):
        a, b = RANK.get(component(imp.source)), RANK.get(component(imp.target))
        if a is None or b is None or imp.type_only:
            continue  # unassigned: test_every_component_is_placed reports it
        if b > a:
            violations.append(f"{imp}: rank {a} imports rank {b}")
    for v in violations:
        print(v)
    assert not violations, f"{len(violations)} upward imports:\n" + "\n".join(violations)


def test_no_component_cycles():
    """The component graph (runtime imports between different components) is acyclic. Each
    cycle is reported as its strongly connected component (Tarjan), the shortest cycle through
    each member, and the imports along those cycles (an upward one is usually the one to cut)."""
    edges = component_edges(all_imports())
    nodes = {c for e in edges for c in e}
    problems = []
    for scc in strongly_connected(nodes, set(edges)):
        problems.append(f"cycle among {{{', '.join(scc)}}}:")
        cycles = shortest_cycles(scc, set(edges))
        on_cycles = set()
        for cycle in cycles:
            problems.append("  " + " -> ".join([*cycle, cycle[0]]))
            on_cycles |= set(zip(cycle, [*cycle[1:], cycle[0]], strict=True))
        for a, b in sorted(on_cycles):
            ra, rb = RANK.get(a, "?"), RANK.get(b, "?")
            up = " (upward)" if isinstance(ra, int) and isinstance(rb, int) and rb > ra else ""
            problems += [f"    {imp}: rank {ra} imports rank {rb}{up}" for imp in edges[a, b]]
    for p in problems:
        print(p)
    assert not problems, "component cycles:\n" + "\n".join(problems)


def test_no_blender_outside_avatar_blender():
    """Only avatar.blender imports bpy, mathutils, bmesh or bpy_extras (at any depth; the
    runtime twin is tests/test_core_without_blender.py)."""
    found = [
        str(imp)
        for imp in all_imports()
        if imp.target.split(".")[0] in BLENDER_MODULES
        and not (imp.source + ".").startswith("avatar.blender.")
    ]
    assert not found, "Blender imports outside avatar.blender:\n" + "\n".join(found)


def test_print_component_graph():
    """Prints each component's rank and what it imports (run with -s to see it). Upward edges
    are marked UP, type-only edges (under TYPE_CHECKING) are marked as such."""
    imports = internal(all_imports())
    present = sorted({component(m) for m in modules()}, key=lambda c: (RANK.get(c, 99), c))
    uses: dict[str, dict[str, bool]] = defaultdict(dict)  # a -> b -> type-only
    for imp in imports:
        a, b = component(imp.source), component(imp.target)
        if a != b:
            uses[a][b] = uses[a].get(b, True) and imp.type_only
    print("\ncomponent graph of avatar (rank: component -> imported components):")
    for a in present:
        ra = RANK.get(a)
        parts = []
        for b in sorted(uses[a], key=lambda c: (RANK.get(c, 99), c)):
            rb = RANK.get(b)
            mark = (
                " type-only"
                if uses[a][b]
                else (" UP" if ra is not None and rb is not None and rb > ra else "")
            )
            parts.append(f"{b}({'?' if rb is None else rb}){mark}")
        print(f"  {'?' if ra is None else ra:>2}: {a} -> {', '.join(parts) or '-'}")
    assert present


@pytest.mark.parametrize(
    ("name", "is_package", "source", "expected"),
    [
        (
            "avatar",
            True,
            "from . import mesh\nfrom .errors import E\n",
            ["avatar.mesh", "avatar.errors"],
        ),
        ("avatar.clothes.binder", False, "from ..io import gltf\n", ["avatar.io.gltf"]),
        ("avatar.clothes", True, "from .binder import f\n", ["avatar.clothes.binder"]),
        ("avatar.clothes.binder", False, "from . import outfit\n", ["avatar.clothes.outfit"]),
        ("avatar.x", False, "def f():\n    import avatar.rig.skeleton\n", ["avatar.rig.skeleton"]),
        ("avatar.x", False, "from avatar.io import NotAModule\n", ["avatar.io"]),
        ("avatar.x", False, "from avatar import Human\n", ["avatar"]),
        ("avatar.x", False, "if TYPE_CHECKING:\n    import avatar.human\n", ["avatar.human"]),
    ],
)
def test_reader_resolves_imports(name, is_package, source, expected):
    """The import reader itself: relative, submodule, function-level and type-only imports."""
    known = {
        "avatar.mesh",
        "avatar.errors",
        "avatar.io.gltf",
        "avatar.clothes.binder",
        "avatar.clothes.outfit",
        "avatar.rig.skeleton",
        "avatar.human",
    }
    imports = read_imports(name, source, is_package, known)
    assert [i.target for i in imports] == expected
    assert all(i.type_only == ("TYPE_CHECKING" in source) for i in imports)
