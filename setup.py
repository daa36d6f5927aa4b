"""Build hook only (the metadata is in pyproject.toml): a wheel carries the top-level ``examples/``
and ``sweeps/`` folders as package data under ``pipeline/shipped_data/``, copied at build time, so the
clone keeps one copy of each file. An editable install reads the clone's folders directly
(``pipeline/shipped.py`` looks there second)."""

from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

SHIPPED = ("examples", "sweeps")  # pipeline.shipped.FOLDERS


class BuildWithShipped(build_py):
    def run(self):
        super().run()
        if getattr(self, "editable_mode", False):
            return
        root = Path(__file__).resolve().parent
        for folder in SHIPPED:
            target = Path(self.build_lib) / "pipeline" / "shipped_data" / folder
            target.mkdir(parents=True, exist_ok=True)
            for path in sorted((root / folder).iterdir()):
                if path.is_file() and path.suffix in (".toml", ".py"):
                    self.copy_file(str(path), str(target / path.name))


setup(cmdclass={"build_py": BuildWithShipped})
