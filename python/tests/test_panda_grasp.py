"""python/examples/panda_grasp.py: the Panda's servoed fingers hold a 0.1 kg cube through
a 0.15 m lift (the commanded height, reached within 2 mm; the cube slips less than 0.1 mm
in the fingers) and the recorded page is written with its frames."""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python" / "examples"))

import panda_grasp  # noqa: E402


def test_panda_lifts_the_cube_without_slipping(tmp_path):
    page = tmp_path / "panda.html"
    gained, slip = panda_grasp.main(page)
    assert abs(gained - 0.15) < 2e-3, gained
    assert abs(slip) < 1e-4, slip
    text = page.read_text()
    assert "panda_leftfinger" in text and len(text) > 10_000
