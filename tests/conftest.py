"""Shared by every test folder (tests/<layer>/): the tests' own helpers in ``tests/data``
(``from data.make_preset_baseline import fingerprint``) import from any folder."""

import sys
from pathlib import Path

TESTS = Path(__file__).resolve().parent
if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))
