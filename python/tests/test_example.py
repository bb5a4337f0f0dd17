"""python/examples/s2_plot.py writes its PNG (matplotlib's Agg backend)."""

import subprocess
import sys

from conftest import ROOT


def test_s2_plot_writes_a_png(tmp_path):
    out = tmp_path / "s2.png"
    p = subprocess.run([sys.executable, str(ROOT / "python" / "examples" / "s2_plot.py"),
                        str(out), "0.1"], capture_output=True, text=True)
    assert p.returncode == 0, p.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
