"""numba's on-disk cache of pkm_pin's compiled functions follows every module compiled
into them (pkm_pin.compiling.install_stamp), not only the file that defines each."""

from __future__ import annotations

import shutil
from pathlib import Path

import pkm_pin
from pkm_pin import compiling
from pkm_pin.compiling import _PackageStamped, compiled_sources, package_stamp, source_stamp
from pkm_pin.engine import core
from pkm_pin.solve import track
from pkm_pin.twists import tree_outputs_many

PACKAGE = Path(pkm_pin.__file__).resolve().parent


def test_pkm_pin_functions_are_cached_with_the_package_stamp():
    """The engine, the leg tracker and the tree pass (cache=True) are located by
    pkm_pin's locator: their stamp is their file's and the package's; the locators are
    installed once, ahead of numba's own."""
    for dispatcher in (core.analyse_into, track, tree_outputs_many):
        locator = dispatcher._cache._impl.locator
        assert isinstance(locator, _PackageStamped)
        own, package = locator.get_source_stamp()
        assert package == package_stamp() and own
    assert compiling.install_stamp()  # again: nothing added
    from numba.core import caching

    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl
    ours = [c for c in impl._locator_classes if issubclass(c, _PackageStamped)]
    assert ours and impl._locator_classes[:len(ours)] == ours


def test_functions_outside_pkm_pin_keep_numbas_locators():
    def f(x):
        return x

    assert f.__module__ != "pkm_pin" and not f.__module__.startswith("pkm_pin.")
    assert _PackageStamped.from_function(f, __file__) is None


def test_the_stamp_follows_every_module_compiled_in(tmp_path):
    """An edit of a module numba compiles code from (the engine's linear algebra, the
    tolerances) changes the stamp, and so invalidates the cached machine code of every
    function; an edit elsewhere (the CLI) does not."""
    root = tmp_path / "pkm_pin"
    shutil.copytree(PACKAGE, root, ignore=shutil.ignore_patterns("__pycache__"))
    names = {p.relative_to(root).as_posix() for p in compiled_sources(root)}
    assert {"engine/linalg.py", "engine/stages.py", "engine/core.py", "solve.py",
            "kernels.py", "twists.py", "tolerances.py"} <= names
    assert "cli.py" not in names
    before = source_stamp(root)
    assert before == package_stamp()
    for name, changes in (("cli.py", False), ("engine/linalg.py", True),
                          ("tolerances.py", True)):
        path = root / name
        text = path.read_text()
        path.write_text(text + "\n# an edit\n")
        assert (source_stamp(root) != before) is changes, name
        path.write_text(text)
        assert source_stamp(root) == before
