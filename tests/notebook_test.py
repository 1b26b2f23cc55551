"""Executes a notebook cell by cell, as Jupyter would, and fails on the first cell that raises:
examples/python/calibrate_a_guide.ipynb in the test suite (ctest -R notebook).

    PYTHONPATH=build/python python3 tests/notebook_test.py NOTEBOOK [--output EXECUTED.ipynb]

The kernel is this interpreter's (a kernel spec written for sys.executable, so that it imports
the lmcal this process imports); the notebook runs in a temporary folder. Exits 77
(ctest: skipped) saying what to install when nbclient, nbformat, ipykernel or the packages the
notebook uses (pandas, matplotlib) are missing."""

import argparse
import importlib.util
import json
import os
import re
import sys
import tempfile
import time

SKIPPED = 77
NEEDED = {"nbclient": "python3-nbclient", "nbformat": "python3-nbformat", "ipykernel": "python3-ipykernel",
          "pandas": "python3-pandas", "matplotlib": "python3-matplotlib"}
ANSI_COLOUR = r"\x1b\[[0-9;]*m"  # IPython's tracebacks are coloured


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("notebook")
    parser.add_argument("--output", help="write the executed notebook (with its outputs) here")
    args = parser.parse_args()
    missing = [module for module in NEEDED if importlib.util.find_spec(module) is None]
    if missing:
        print(f"skipped: {', '.join(missing)} not installed for {sys.executable} "
              f"(Debian: apt-get install {' '.join(NEEDED[m] for m in missing)})")
        return SKIPPED

    import nbclient
    import nbformat

    notebook = nbformat.read(args.notebook, as_version=4)
    with tempfile.TemporaryDirectory(prefix="lmcal-notebook-") as folder:
        # This interpreter's kernel, found before any other.
        spec = os.path.join(folder, "kernels", "python3")
        os.makedirs(spec)
        with open(os.path.join(spec, "kernel.json"), "w") as f:
            json.dump({"argv": [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"],
                       "display_name": "Python 3", "language": "python"}, f)
        os.environ["JUPYTER_PATH"] = folder + os.pathsep + os.environ.get("JUPYTER_PATH", "")
        os.environ.pop("MPLBACKEND", None)  # the kernel's own (inline) backend
        os.environ.setdefault("PYDEVD_DISABLE_FILE_VALIDATION", "1")  # else the kernel's debugger warns on stderr
        client = nbclient.NotebookClient(notebook, timeout=600, kernel_name="python3",
                                         resources={"metadata": {"path": folder}})
        start = time.perf_counter()
        try:
            client.execute()
        except nbclient.exceptions.CellExecutionError as e:
            print(f"{args.notebook}: a cell failed:\n{re.sub(ANSI_COLOUR, '', str(e))}")
            return 1
        finally:
            if args.output:
                nbformat.write(notebook, args.output)
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    figures = sum(1 for cell in code for out in cell.get("outputs", []) if "image/png" in out.get("data", {}))
    print(f"{args.notebook}: {len(code)} code cells ran in {time.perf_counter() - start:.1f} s ({figures} figures)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
