"""``python -m studies all``: the report beside the paper's claims, the up-to-date skip, failures kept apart, and the
report opened in a real headless browser (Debian chromium) with every image it references present and a PNG."""

import json
import shutil
import struct
import subprocess
import zlib
from html.parser import HTMLParser
from pathlib import Path

import pytest

from studies import all as all_studies
from studies.__main__ import main

THEORY = ["fig2b", "fig3b", "torsion-theory"]            # closed-form studies: seconds, so the report test is fast
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory):
    """A quick report of the theory studies, made through the command line with two worker processes."""
    out = tmp_path_factory.mktemp("results")
    assert main(["all", "--out", str(out), "--quick", "--only", ",".join(THEORY), "--jobs", "2"]) == 0
    return out


def test_report_shows_each_study_with_claim_error_time_and_verdict(quick_report):
    html = (quick_report / "index.html").read_text()
    markdown = (quick_report / "REPORT.md").read_text()
    for name in THEORY:
        record = json.loads((quick_report / f"{name}.summary.json").read_text())
        assert record["status"] == "ok" and record["quick"] is True and record["wall_time"] > 0
        assert record["summary"]["max_error"] < 1e-9                 # closed form against quadrature: round-off
        assert f"![{name}]({name}.png)" in markdown and f"src='{name}.png'" in html
    from studies._report import CLAIMS

    for name in THEORY:
        assert CLAIMS[name].claim in markdown
    assert "**Verdict: reproduced**" in markdown                       # fig2b and fig3b, by their rules
    assert "**Verdict: partly**" in markdown                           # torsion: eq. 6 slides too early
    assert "total wall time of this run" in markdown and "Quick (coarse) settings" in markdown


def test_second_run_reuses_what_is_up_to_date(quick_report):
    stamps = {name: (quick_report / ".stamps" / f"{name}.json").stat().st_mtime_ns for name in THEORY}
    summaries = {name: (quick_report / f"{name}.summary.json").read_text() for name in THEORY}
    result = all_studies.run(quick_report, quick=True, jobs=2, only=THEORY)
    assert result["reused"] == THEORY and result["computed"] == []
    assert all((quick_report / ".stamps" / f"{n}.json").stat().st_mtime_ns == stamps[n] for n in THEORY)
    assert all((quick_report / f"{n}.summary.json").read_text() == summaries[n] for n in THEORY)
    assert "up to date, reused" in (quick_report / "REPORT.md").read_text()


def test_other_settings_or_a_lost_output_are_not_up_to_date(quick_report):
    modules, _ = all_studies.discover()
    assert all_studies.is_up_to_date(quick_report, "fig2b", modules["fig2b"], quick=True)
    assert not all_studies.is_up_to_date(quick_report, "fig2b", modules["fig2b"], quick=False)
    (quick_report / "fig3b.png").unlink()
    result = all_studies.run(quick_report, quick=True, jobs=1, only=THEORY)
    assert result["computed"] == ["fig3b"] and sorted(result["reused"]) == ["fig2b", "torsion-theory"]
    assert (quick_report / "fig3b.png").is_file()


def test_hash_covers_the_study_its_helpers_and_the_packages():
    modules, _ = all_studies.discover()
    files = {path.name for path in all_studies.source_files(modules["fig3"])}
    assert {"fig3.py", "bench.py", "_output.py", "solver.py", "elasticity.py"} <= files
    assert "_report.py" not in files and "fig4.py" not in files


def test_a_failing_study_is_reported_and_the_others_are_kept(tmp_path, monkeypatch):
    from studies import _report, fig3b

    def broken(out_dir, quick=False):
        raise RuntimeError("forced failure for the test")

    monkeypatch.setattr(fig3b, "run", broken)
    monkeypatch.setitem(_report.CLAIMS, "fig99", _report.claim_for("fig99"))     # tabled, but no module
    with pytest.raises(RuntimeError, match="fig3b: RuntimeError: forced failure"):
        all_studies.run(tmp_path, quick=True, jobs=1, only=["fig2b", "fig3b", "fig99"])
    assert json.loads((tmp_path / "fig2b.summary.json").read_text())["status"] == "ok"
    failed = json.loads((tmp_path / "fig3b.summary.json").read_text())
    assert failed["status"] == "failed" and "forced failure" in failed["traceback"]
    assert not (tmp_path / ".stamps" / "fig3b.json").exists()                    # so the next run tries again
    markdown = (tmp_path / "REPORT.md").read_text()
    assert "| **failed** |" in markdown and "forced failure for the test" in markdown
    assert "| **not available** |" in markdown and "![fig2b](fig2b.png)" in markdown
    assert "![fig3b]" not in markdown                                          # no figure shown for a failure


def test_unknown_study_names_are_refused(tmp_path):
    with pytest.raises(ValueError, match="unknown study name"):
        all_studies.run(tmp_path, quick=True, only=["no-such-study"])


# -------------------------------------------------------------------------------------------------------------
# the report in a real browser

CHROMIUM = next((shutil.which(name) for name in ("chromium", "chromium-browser", "google-chrome")
                 if shutil.which(name)), None)
BROWSER_TIMEOUT = 90        # s: a cold headless start takes a few seconds; a slow CI machine more


class _Images(HTMLParser):
    def __init__(self):
        super().__init__()
        self.sources = []

    def handle_starttag(self, tag, attrs):
        if tag == "img":
            self.sources.append(dict(attrs).get("src"))


def _chromium(profile: Path, *arguments: str) -> subprocess.CompletedProcess:
    command = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
               "--disable-background-networking", "--disable-component-update", "--disable-sync",
               f"--user-data-dir={profile}", *arguments]
    return subprocess.run(command, capture_output=True, text=True, timeout=BROWSER_TIMEOUT, check=True)


def _png_size(data: bytes) -> tuple[int, int]:
    """Width and height from a PNG's IHDR chunk, after checking the signature and the chunk's CRC."""
    assert data[:8] == PNG_SIGNATURE
    length, kind = struct.unpack(">I4s", data[8:16])
    assert kind == b"IHDR" and length == 13
    assert struct.unpack(">I", data[29:33])[0] == zlib.crc32(data[12:29])
    return struct.unpack(">II", data[16:24])


@pytest.mark.skipif(CHROMIUM is None, reason="no headless browser: apt-get install -y chromium (see .ci/run)")
def test_report_loads_in_a_headless_browser_with_all_its_images(quick_report, tmp_path):
    page = (quick_report / "index.html").resolve()
    dom = _chromium(tmp_path / "profile", "--dump-dom", page.as_uri()).stdout
    assert "Fingertip contact: figures against the paper's claims" in dom
    images = _Images()
    images.feed(dom)
    assert sorted(images.sources) == sorted(f"{name}.png" for name in THEORY)
    for source in images.sources:
        width, height = _png_size((page.parent / source).read_bytes())
        assert width > 100 and height > 100
    shot = tmp_path / "page.png"
    _chromium(tmp_path / "profile", f"--screenshot={shot}", "--window-size=1200,2000", page.as_uri())
    assert _png_size(shot.read_bytes()) == (1200, 2000)
