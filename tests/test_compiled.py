"""numba kernels cached in a folder keyed by every kernel module's source, so an edit anywhere recompiles all."""

import numpy as np

from fem import compiled


def test_kernel_cache_folder_changes_when_any_kernel_source_changes(tmp_path, monkeypatch):
    root = tmp_path / "repo"
    for package in compiled.KERNEL_PACKAGES:
        (root / package).mkdir(parents=True)
    (root / "fem" / "compiled.py").write_text("# njit_cached\n")
    kernel = root / "contact" / "kernel.py"
    kernel.write_text("from fem.compiled import njit_cached\n")
    (root / "controller" / "plain.py").write_text("x = 1\n")
    monkeypatch.setenv("FINGERTIP_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(compiled, "__file__", str(root / "fem" / "compiled.py"))

    def folder():
        compiled.kernel_cache_dir.cache_clear()
        return compiled.kernel_cache_dir()

    first = folder()
    assert first.parent == tmp_path / "cache" / "numba"
    (root / "controller" / "plain.py").write_text("x = 2\n")          # not a kernel module: same folder
    assert folder() == first
    kernel.write_text("from fem.compiled import njit_cached\n# edited\n")   # a kernel module edited: a new folder
    assert folder() != first
    compiled.kernel_cache_dir.cache_clear()


def test_cached_kernel_runs_and_writes_its_cache_in_the_keyed_folder(tmp_path, monkeypatch):
    from numba import config

    monkeypatch.setenv("FINGERTIP_CACHE", str(tmp_path))
    compiled.kernel_cache_dir.cache_clear()
    before = config.CACHE_DIR

    @compiled.njit_cached
    def doubled(values):
        return 2.0 * values

    assert np.array_equal(doubled(np.arange(3.0)), [0.0, 2.0, 4.0])
    assert config.CACHE_DIR == before                                   # numba's global setting is left as it was
    assert any(compiled.kernel_cache_dir().rglob("*.nbi"))              # the index went to the keyed folder
    compiled.kernel_cache_dir.cache_clear()
