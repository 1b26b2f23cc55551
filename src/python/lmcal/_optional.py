"""The optional packages some methods use (pandas for ``to_dataframe()``, matplotlib for
``plot()``), imported when a method first needs them, so that ``import lmcal`` needs NumPy alone."""

import importlib

# module -> (Debian package, pip package)
_PACKAGES = {"pandas": ("python3-pandas", "pandas"), "matplotlib.pyplot": ("python3-matplotlib", "matplotlib")}


def require(module: str, what: str):
    """``module`` imported, or ImportError saying that ``what`` needs it and how to install it."""
    try:
        return importlib.import_module(module)
    except ImportError as e:
        debian, pip = _PACKAGES[module]
        raise ImportError(f"{what} needs {pip}, which is not installed: `apt-get install {debian}` (Debian) "
                          f"or `pip install {pip}`") from e
