"""The core's layout: its subpackages form layers, each importing only from its own layer and the layers below; no
module reads another's private names; every public name of ``rdmp_gym`` stays importable from ``rdmp_gym``."""

import ast
import itertools
from pathlib import Path

import pytest

import rdmp_gym

ROOT = Path(__file__).resolve().parent.parent
CORE = ROOT / "rdmp_gym"

#: the entries of ``rdmp_gym/``, bottom to top: each imports only from its own layer and those before it
LAYERS = (
    "validation",    # input checks shared by every layer
    "signals",       # sampled motion without a DMP: demonstrations, filters, segmentation
    "dmp",           # the DMP: formulation, rollout, fit to demonstrations, poses, files
    "recordings",    # whole recordings and their fit: sessions, poses, pose CSV files
    "synthetic",     # data with known truth
    "figures",       # plots and the paper's figures
    "__init__",      # the public names
)

#: ``rdmp_gym.__all__`` when the core was laid out in subpackages; none of these names may go
PUBLIC_NAMES = (ROOT / "tests" / "data" / "core_public_names.txt").read_text().split()


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _imports(path: Path) -> list[tuple[ast.AST, str, list[str]]]:
    """``(node, absolute module, imported names)`` of every import of ``rdmp_gym`` in ``path`` (relative ones
    resolved; ``from . import x`` gives the package and ``["x"]``)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            found.append((node, target, [alias.name for alias in node.names]))
        elif isinstance(node, ast.Import):
            found += [(node, alias.name, []) for alias in node.names]
    return [entry for entry in found if entry[1] == "rdmp_gym" or entry[1].startswith("rdmp_gym.")]


def _layer(module: str) -> str:
    """The entry of ``rdmp_gym/`` that holds ``module`` (``__init__`` for the package itself)."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _core_files() -> list[Path]:
    return sorted(CORE.rglob("*.py"))


def test_every_entry_of_the_core_has_a_layer() -> None:
    entries = {path.stem if path.is_file() else path.name for path in CORE.iterdir()
               if path.name != "__pycache__" and (path.is_dir() or path.suffix == ".py")}
    assert entries == set(LAYERS)


def test_no_import_runs_from_a_lower_layer_to_a_higher_one() -> None:
    upward = []
    for path in _core_files():
        own = LAYERS.index(_layer(_module_name(path)))
        for node, target, _ in _imports(path):
            layer = _layer(target)
            if layer not in LAYERS or LAYERS.index(layer) > own:
                upward.append(f"{path.relative_to(ROOT)}:{node.lineno} imports {target} ({layer})")
    assert not upward


def test_each_subpackage_imports_the_layer_below_it() -> None:
    """The order of :data:`LAYERS` is the only one the import graph allows (the root ``__init__`` aside)."""
    used = {(_layer(_module_name(path)), _layer(target)) for path in _core_files() for _, target, _ in _imports(path)}
    for below, above in itertools.pairwise(LAYERS[:-1]):
        assert (above, below) in used, f"{above} imports nothing of {below}"


def test_no_core_module_reads_a_private_name_of_another() -> None:
    found = []
    for path in _core_files():
        tree = ast.parse(path.read_text())
        modules = set()     # names bound to core modules: from . import quaternion
        for node, _, names in _imports(path):
            if isinstance(node, ast.ImportFrom):
                found += [f"{path.relative_to(ROOT)}:{node.lineno} {name}" for name in names if name.startswith("_")]
                if node.module is None:
                    modules.update(alias.asname or alias.name for alias in node.names)
            else:
                modules.update(alias.asname or alias.name.split(".")[0] for alias in node.names)
        found += [f"{path.relative_to(ROOT)}:{node.lineno} {node.value.id}.{node.attr}" for node in ast.walk(tree)
                  if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name)
                  and node.value.id in modules and node.attr.startswith("_") and not node.attr.startswith("__")]
    assert not found


@pytest.mark.parametrize("name", PUBLIC_NAMES)
def test_every_public_name_stays_importable_from_rdmp_gym(name: str) -> None:
    assert name in rdmp_gym.__all__
    namespace: dict = {}
    exec(f"from rdmp_gym import {name}", namespace)
    assert namespace[name] is getattr(rdmp_gym, name)
