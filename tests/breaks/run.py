"""Run the catalogue of breaks (``tests/breaks/catalogue.py``): each break is applied in a
scratch copy of the tree, its tests run there, and the break reverted; prints caught or MISSED
for each and exits 1 if any was missed. Usage (from the checkout, after the README's test
command installed the tools): ``.venv/bin/python tests/breaks/run.py [-k WORDS]``.
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from catalogue import BREAKS, Break

ROOT = Path(__file__).resolve().parents[2]


def scratch_copy(into: Path) -> Path:
    """The tracked files of the checkout (the working tree's versions) copied into ``into``."""
    files = subprocess.run(["git", "ls-files", "-co", "--exclude-standard"], cwd=ROOT,
                           capture_output=True, text=True, check=True).stdout.split()
    for name in files:
        source = ROOT / name
        if source.is_file():
            target = into / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, target)
    return into


def run_break(tree: Path, b: Break) -> tuple[str, float]:
    """('caught' | 'MISSED' | 'ERROR: ...', seconds) for one break in the scratch ``tree``."""
    originals = {}
    try:
        for file, text, replacement in b.edits:
            path = tree / file
            source = originals.setdefault(path, path.read_text())
            current = path.read_text()
            if current.count(text) != 1:
                return (f"ERROR: the text to break occurs {source.count(text)} times in "
                        f"{file} (expected once: update the catalogue)"), 0.0
            path.write_text(current.replace(text, replacement))
        env = dict(os.environ, PYTHONPATH=str(tree))
        start = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-n0",
                               "-p", "no:cacheprovider", *b.tests], cwd=tree, env=env,
                              capture_output=True, text=True, timeout=900)
        took = time.monotonic() - start
        if done.returncode == 1:
            return "caught", took
        if done.returncode == 0:
            return "MISSED", took
        tail = (done.stdout + done.stderr).strip().splitlines()[-1:] or ["?"]
        return f"ERROR: pytest exit {done.returncode}: {tail[0]}", took
    finally:
        for path, text in originals.items():
            path.write_text(text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-k", default="", help="only the breaks whose name contains this")
    args = parser.parse_args(argv)
    chosen = [b for b in BREAKS if args.k.lower() in b.name.lower()]
    failed = 0
    with tempfile.TemporaryDirectory(prefix="drill_sim_breaks_") as scratch:
        tree = scratch_copy(Path(scratch))
        # unbroken, every named test passes in the scratch copy (else "caught" means nothing)
        tests = sorted({t for b in chosen for t in b.tests})
        done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-n", "2",
                               "-p", "no:cacheprovider", *tests], cwd=tree,
                              env=dict(os.environ, PYTHONPATH=str(tree)),
                              capture_output=True, text=True, timeout=1800)
        if done.returncode != 0:
            print(done.stdout[-3000:] + done.stderr[-2000:])
            print("the catalogue's tests fail on the unbroken tree: fix them first")
            return 2
        print(f"{len(tests)} tests pass unbroken; {len(chosen)} breaks, each in a scratch "
              "copy of the tree", flush=True)
        for i, b in enumerate(chosen, 1):
            verdict, took = run_break(tree, b)
            failed += verdict != "caught"
            print(f"[{i:2d}/{len(chosen)}] {verdict:<7} {took:5.1f} s  {b.name}", flush=True)
    print(f"{len(chosen) - failed} caught, {failed} missed or broken")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
