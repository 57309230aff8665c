import os
import shutil

import pytest


@pytest.fixture(scope="session")
def cli():
    """The wetcloth program (ctest sets WETCLOTH)."""
    path = os.environ.get("WETCLOTH") or shutil.which("wetcloth")
    if not path:
        pytest.skip("WETCLOTH (the wetcloth program) is not set")
    return path


@pytest.fixture(scope="session")
def source_dir():
    return os.environ.get("WETCLOTH_SOURCE_DIR") or os.path.abspath(
        os.path.join(os.path.dirname(__file__), "..", ".."))
