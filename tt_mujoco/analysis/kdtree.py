"""SciPy's k-d tree, without the rest of ``scipy.spatial``.

``from scipy.spatial import cKDTree`` runs the package's ``__init__``, which imports all of
``scipy.spatial`` (rotations, triangulations, distances, and ``scipy.linalg`` under them): a
new process pays that for the first k-d tree a run's metrics make (``benchmarks/
bench_cold_start.py``). The tree is the package's extension module ``_ckdtree`` alone, which
:func:`kd_tree_class` loads under its own name; where it cannot (another SciPy's layout), the
package's import serves, and the class is the same either way.
"""

from __future__ import annotations

import importlib.machinery
import importlib.util
import sys
from pathlib import Path

__all__ = ["kd_tree_class"]

_NAME = "scipy.spatial._ckdtree"


def kd_tree_class():
    """SciPy's ``cKDTree`` class, its extension module loaded alone where it can be."""
    module = sys.modules.get(_NAME) or _load_alone()
    tree = getattr(module, "cKDTree", None)
    if tree is None:
        from scipy import spatial

        tree = spatial.cKDTree
    return tree


def _load_alone():
    """The module ``scipy.spatial._ckdtree`` loaded from its file (None where it is not found
    or does not load): what the package's ``__init__`` would import first."""
    scipy_spec = importlib.util.find_spec("scipy")
    if scipy_spec is None or not scipy_spec.submodule_search_locations:
        return None
    folder = Path(next(iter(scipy_spec.submodule_search_locations))) / "spatial"
    for suffix in importlib.machinery.EXTENSION_SUFFIXES:
        file = folder / f"_ckdtree{suffix}"
        if file.is_file():
            break
    else:
        return None
    spec = importlib.util.spec_from_file_location(_NAME, file)
    module = importlib.util.module_from_spec(spec)
    sys.modules[_NAME] = module  # one module, which the package's import later finds
    try:
        spec.loader.exec_module(module)
    except Exception:  # another SciPy: the package's own import serves
        sys.modules.pop(_NAME, None)
        return None
    return module
