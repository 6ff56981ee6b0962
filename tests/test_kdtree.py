"""SciPy's k-d tree loaded without the rest of scipy.spatial (tt_mujoco.analysis.kdtree)."""

import subprocess
import sys

from tt_mujoco.analysis import kdtree


def test_the_tree_comes_alone_and_is_the_package_s_class():
    """A new process that makes a run's metrics needs the tree, not rotations or
    triangulations: the package's __init__ is not run, and a later import of the package
    finds the same class."""
    script = (
        "import sys\n"
        "from tt_mujoco.analysis.kdtree import kd_tree_class\n"
        "tree = kd_tree_class()\n"
        "alone = 'scipy.spatial' not in sys.modules and 'scipy.linalg' not in sys.modules\n"
        "import scipy.spatial\n"
        "nearest = tree([[0.0, 0.0], [1.0, 0.0]]).query([0.9, 0.0])[1]\n"
        "print(alone, tree is scipy.spatial.cKDTree, nearest)\n"
    )
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["True", "True", "1"]


def test_where_it_cannot_be_loaded_alone_the_package_serves(monkeypatch):
    from scipy import spatial

    monkeypatch.delitem(sys.modules, "scipy.spatial._ckdtree", raising=False)
    monkeypatch.setattr(kdtree, "_load_alone", lambda: None)
    assert kdtree.kd_tree_class() is spatial.cKDTree
