"""The import graph is one-way, the simulator knows no robot logic, and the mission logic
runs without the simulator.

The graph is read from the source: every ``import`` statement, including those inside
functions and the typing-only ones under ``if TYPE_CHECKING:`` (a cycle hidden behind a
type hint is still two modules that each need the other to be understood). Importing
``a.b.c`` counts as importing its packages ``a.b`` too, since Python runs their
``__init__`` first.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"


def _modules() -> dict[str, Path]:
    out = {}
    for path in (SRC / "tetherland").rglob("*.py"):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
        out[".".join(parts)] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, *, type_checking: bool = True) -> set[str]:
    """Modules imported anywhere in ``tree``; with ``type_checking=False`` not those under
    ``if TYPE_CHECKING:`` (the runtime imports only)."""
    found: set[str] = set()

    def visit(node: ast.AST) -> None:
        if not type_checking and isinstance(node, ast.If) and _is_type_checking(node):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
            found.update(f"{node.module}.{a.name}" for a in node.names)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(tree)
    return found


def import_graph(*, type_checking: bool = True) -> dict[str, set[str]]:
    """Module -> the tetherland modules it imports (with their parent packages), typing-only
    imports included unless ``type_checking`` is False."""
    modules = _modules()
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        targets: set[str] = set()
        for imported in _imports(ast.parse(path.read_text()), type_checking=type_checking):
            parts = imported.split(".")
            for i in range(2, len(parts) + 1):
                target = ".".join(parts[:i])
                inside = name == target or name.startswith(target + ".")
                if target in modules and not inside:
                    targets.add(target)
        graph[name] = targets
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one node (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def strong(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    sys.setrecursionlimit(max(sys.getrecursionlimit(), 10_000))
    for v in sorted(graph):
        if v not in index:
            strong(v)
    return found


def test_the_cycle_finder_finds_a_cycle():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles({"a": {"b"}, "b": set()}) == []


def _reachable(graph: dict[str, set[str]], start: list[str]) -> set[str]:
    seen: set[str] = set()
    stack = list(start)
    while stack:
        for target in graph.get(stack.pop(), ()):
            if target not in seen:
                seen.add(target)
                stack.append(target)
    return seen


def test_typing_only_imports_are_part_of_the_graph():
    code = "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from tetherland.x import Y\n"
    tree = ast.parse(code)
    assert "tetherland.x" in _imports(tree)
    assert "tetherland.x" not in _imports(tree, type_checking=False)
    runtime, full = import_graph(type_checking=False), import_graph()
    assert all(runtime[m] <= full[m] for m in runtime)
    assert any(runtime[m] < full[m] for m in runtime)  # the package has typing-only imports


def test_the_module_import_graph_has_no_cycles():
    graph = import_graph()
    assert len(graph) > 50  # the whole package was read
    assert cycles(graph) == []


def test_the_package_import_graph_has_no_cycles():
    packages: dict[str, set[str]] = {}
    for module, targets in import_graph().items():
        top = ".".join(module.split(".")[:2])
        packages.setdefault(top, set()).update(
            t2 for t in targets if (t2 := ".".join(t.split(".")[:2])) != top
        )
    assert "tetherland.mission" in packages["tetherland.methods"]
    assert cycles(packages) == []


@pytest.mark.parametrize(
    "package",
    ["tetherland.mission", "tetherland.methods", "tetherland.verdict", "tetherland.control",
     "tetherland.estimation", "tetherland.planning", "tetherland.analysis"],
)  # fmt: skip
def test_robot_side_packages_do_not_import_mujoco(package):
    code = f"import sys, {package}; print('mujoco' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


ROBOT_PACKAGES = ("mission", "planning", "control", "estimation")


def test_the_simulator_imports_no_robot_logic():
    """sim/ (the plant, sensors, faults, the runner) reaches none of the robot's packages,
    directly or through anything it imports: the world the robot is judged in knows nothing
    of its decisions."""
    graph = import_graph()
    sim = [m for m in graph if m == "tetherland.sim" or m.startswith("tetherland.sim.")]
    assert len(sim) > 10  # every module of the simulator was read
    reached = {m.split(".")[1] for m in _reachable(graph, sim)}
    assert "models" in reached and "config" in reached  # the vehicle model and the scenario
    assert reached.isdisjoint(ROBOT_PACKAGES), sorted(reached & set(ROBOT_PACKAGES))


def test_a_command_loads_its_own_modules_only():
    """`tetherland show` loads neither the simulator, the solvers, numba nor matplotlib
    (nor does a campaign's spawned worker, which runs the console script again as its
    ``__main__``): the commands' modules are imported when a command runs. And the closed
    loop does not load scipy.optimize (0.5 s per process), which no mission calls."""
    code = (
        "import sys\n"
        "from tetherland.cli import main\n"
        "assert main(['show', 'slope50']) == 0\n"
        "heavy = ('mujoco', 'casadi', 'numba', 'matplotlib', 'scipy', 'tetherland.campaign',\n"
        "         'tetherland.analysis', 'tetherland.sim.plant', 'tetherland.runs')\n"
        "print('loaded', sorted(m for m in heavy if m in sys.modules))\n"
        "import tetherland.runs.closed_loop\n"
        "print('scipy.optimize', 'scipy.optimize' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.splitlines()[-2:] == ["loaded []", "scipy.optimize False"], out.stdout


def test_the_help_lists_every_command_built_from_its_module():
    from tetherland.cli import COMMANDS, _command

    group = _command()
    assert list(group.commands) == list(COMMANDS)
    for name in COMMANDS:
        assert group.commands[name].name == name


def test_the_root_help_lists_the_commands_as_they_describe_themselves_without_loading_them():
    """``tetherland --help`` lists each command with the first sentence of its own help
    (:data:`tetherland.cli.SUMMARIES`), shortened as click shortens it, and imports none of
    the commands' modules (each loads the simulator or the solvers: 2-3 s)."""
    import typer
    import typer.core

    from tetherland.cli import COMMANDS, SUMMARIES, _command

    code = (
        "import sys\nfrom tetherland.cli import main\nmain(['--help'])\n"
        "print(sorted(m for m in sys.modules if m.startswith('tetherland.cli.')))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    *help_lines, loaded = out.stdout.splitlines()
    assert loaded == "[]"
    group = _command()
    assert list(SUMMARIES) == list(COMMANDS)
    for name in COMMANDS:  # the summary is the command's own short help, whole
        assert group.commands[name].get_short_help_str(10_000) == SUMMARIES[name]
    # the listing equals the one typer writes from the built commands
    ctx = typer.Context(group, info_name="tetherland")
    expected = ctx.make_formatter()
    typer.core.TyperGroup.format_commands(group, ctx, expected)
    listed = expected.getvalue().splitlines()
    assert len(listed) == len(COMMANDS) + 1 and listed[0] == "Commands:"
    start = help_lines.index("Commands:")
    assert help_lines[start : start + len(listed)] == listed
