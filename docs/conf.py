"""Sphinx configuration of the taopt documentation site.

Build (after ``pip install ".[docs]"``) with ONE command from the repository root::

    python docs/build.py

which runs ``sphinx-build -W --keep-going -n -b html docs docs/_build/html``: every warning
is an error, and ``-n`` (nitpicky) makes every cross-reference into taopt resolve or fail the
build. The notebooks of ``notebooks/`` are included through the symbolic link
``docs/notebooks`` (no copy) and executed at build time by myst-nb.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
# The checkout root makes ``import taopt`` (with taopt.models and taopt.heuristics mapped by
# taopt/__init__.py) resolve to this checkout, installed or not.
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(HERE))

from generated import generated_pages  # noqa: E402  (docs/generated.py)

import taopt  # noqa: E402

for _name, _text in generated_pages().items():
    _page = HERE / _name
    _page.parent.mkdir(parents=True, exist_ok=True)
    if not _page.is_file() or _page.read_text(encoding="utf-8") != _text:
        _page.write_text(_text, encoding="utf-8")

project = "taopt"
author = "the taopt developers"
copyright = "2026, the taopt developers (MIT licence)"
release = taopt.__version__
version = release

extensions = [
    "myst_nb",  # Markdown pages (MyST) and notebooks executed at build time
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",  # numpydoc docstrings
    "sphinx.ext.mathjax",
    # MathJax 3 served from the site itself (_static/mathjax), not from a CDN: the site reads
    # offline, and the browser check in CI sees every resource load
    "sphinx-mathjax-offline",
    "sphinx.ext.viewcode",
]

source_suffix = {".rst": "restructuredtext", ".md": "myst-nb", ".ipynb": "myst-nb"}
root_doc = "index"
exclude_patterns = [
    "_build",
    "**.ipynb_checkpoints",
    "reproduction/data",
    "reproduction/counterexamples",
    "README.md",
    "_includes",  # generated fragments, included into pages (docs/generated.py)
]

# -- HTML ----------------------------------------------------------------------------------
html_theme = "furo"
html_title = f"taopt {release}"
html_static_path = ["_static"]
html_favicon = "_static/favicon.svg"
html_show_sourcelink = False

# -- MyST / myst-nb --------------------------------------------------------------------------
myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist"]
myst_heading_anchors = 3  # `[text](page.md#a-heading)` links resolve to heading slugs
myst_dmath_double_inline = True
# Notebooks stay output-stripped in git; they are executed at every build ("force"), so the
# site always shows what the current code computes. TAOPT_DOCS_EXECUTE=cache reuses the
# outputs of an unchanged notebook between local builds (docs/_build/.jupyter_cache).
nb_execution_mode = os.environ.get("TAOPT_DOCS_EXECUTE", "force")
nb_execution_timeout = 900
nb_execution_raise_on_error = True  # a failing assert in a notebook fails the build
nb_execution_show_tb = True
nb_execution_cache_path = str(HERE / "_build" / ".jupyter_cache")
nb_merge_streams = True

# -- autodoc / napoleon -------------------------------------------------------------------
autodoc_default_options = {
    "members": True,
    "member-order": "bysource",
    "show-inheritance": False,
    # a package documents what it defines itself; re-exports are documented where defined
    # (and the top-level names once, on the page of `taopt`)
    "ignore-module-all": True,
    "undoc-members": True,
}
autodoc_typehints = "description"
autodoc_typehints_format = "short"
autodoc_preserve_defaults = True
autosummary_generate = True  # stub pages in docs/api/generated (not in git)
autosummary_imported_members = False
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
# Types are free text in numpydoc ("(n, n) array", "sequence of int"): shown as written, not
# turned into cross-references (whose tokens, such as "n", would match arbitrary attributes).
napoleon_use_param = False
# "Attributes" rendered like "Parameters": the attributes themselves are documented once,
# from the class (dataclass fields), so the section must not create a second description.
napoleon_custom_sections = [("Attributes", "params_style")]
templates_path = ["_templates"]

# -- strictness ----------------------------------------------------------------------------
# `-n` checks every cross-reference. References into taopt must resolve. References to other
# libraries (numpy, cvxpy, ...) and the free-text types of numpydoc ("numpy arrays",
# "array of shape (n, n)") cannot be resolved without intersphinx inventories, which would
# have to be downloaded at build time; they are ignored, and only they.
nitpicky = True
_EXTERNAL = (
    "numpy|np|scipy|cvxpy|cp|networkx|nx|pandas|pd|matplotlib|casadi|highspy|jsonschema|dask|"
    "distributed|ortools|pyvrp|tqdm|concurrent|multiprocessing|pathlib|json|typing|collections|"
    "functools|itertools|math|os|sys|logging|argparse|subprocess|signal|random|dataclasses|io|"
    "filelock|threading|atexit|contextlib|ctypes|time|tempfile|warnings|selenium|importlib"
)
nitpick_ignore_regex = [
    # a type in a docstring or annotation that does not name something in taopt
    # (builtins, other libraries, numpydoc's free text such as "array of shape (n, n)")
    (r"py:class", r"(?!taopt\.).*"),
    # a function, method, attribute or module of another library
    (r"py:(obj|data|exc|func|meth|attr|mod)", rf"({_EXTERNAL})(\..*)?"),
    # private helpers (leading underscore) are named in docstrings but are not API
    (r"py:.*", r"(taopt(\.\w+)*\.)?_\w+(\.\w+)*"),
    # the standard library's exception, named bare in numpydoc "Raises" sections
    (r"py:exc", r"BrokenProcessPool"),
]
suppress_warnings = [
    # myst-nb renders matplotlib figures as image/png; no other mime types are expected
    "mystnb.unknown_mime_type",
    # "more than one target found" for a bare word that is also an attribute name somewhere
    # (a signature's ``bytes``, a "positions" or "iterations" in prose); unresolved targets
    # still fail the build
    "ref.python",
]


# -- docstrings as their authors meant them ------------------------------------------------
# taopt's docstrings write the thesis's notation in plain text: |A| (the number of
# capabilities), |R_i|, |S|. reStructuredText would read "|A|" as a substitution reference
# and fail; taopt never uses substitutions, so every "|" outside inline literals, literal
# blocks and doctest lines is escaped before the docstring is parsed.
_LITERAL = re.compile(r"(``.*?``)")


def _escape_bars(line: str) -> str:
    parts = _LITERAL.split(line)
    return "".join(p if i % 2 else p.replace("|", r"\|") for i, p in enumerate(parts))


def _plain_bars(app, what, name, obj, options, lines: list[str]) -> None:
    literal_indent = None  # indentation of the paragraph that opened a literal block
    for k, line in enumerate(lines):
        stripped = line.strip()
        indent = len(line) - len(line.lstrip())
        if literal_indent is not None:
            if not stripped or indent > literal_indent:
                continue
            literal_indent = None
        if stripped.startswith((">>>", "...")) or "|" not in line:
            pass
        else:
            lines[k] = _escape_bars(line)
        if stripped.endswith("::"):
            literal_indent = indent


# -- references to re-exported names --------------------------------------------------------
# taopt documents every object once, in the module that defines it (taopt.routing.problem.
# AssignmentProblem); docstrings also name it as users import it (taopt.AssignmentProblem,
# taopt.models.solve_routing, or solve_routing inside a module that imports it). Such a
# reference is resolved by importing the name and following it to the object's defining
# module. A name that cannot be imported, or whose object is not documented, still fails.
def _import_dotted(name: str):
    import importlib

    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except Exception:  # noqa: BLE001 - any failure means "not this split"
            continue
        try:
            for attr in parts[cut:]:
                obj = getattr(obj, attr)
        except AttributeError:
            return None
        return obj
    return None


def _documented_binding(domain, name: str, obj) -> str | None:
    last = name.rsplit(".", 1)[-1]
    for fullname, entry in domain.objects.items():
        if entry.objtype == "data" and fullname.endswith("." + last) and fullname != name:
            if obj is not None and _import_dotted(fullname) is obj:
                return fullname
    return None


def _resolve_reexport(app, env, node, contnode):
    if node.get("refdomain") != "py":
        return None
    target = node.get("reftarget", "")
    module, cls = node.get("py:module"), node.get("py:class")
    candidates = [target]
    if module and not target.startswith("taopt"):
        if cls:
            candidates.append(f"{module}.{cls}.{target}")
        candidates.append(f"{module}.{target}")
    domain = env.get_domain("py")
    for name in candidates:
        if not name.startswith("taopt"):
            continue
        obj = _import_dotted(name)
        qualname = getattr(obj, "__qualname__", None)
        where = getattr(obj, "__module__", None)
        if not (isinstance(qualname, str) and isinstance(where, str)):
            # a constant (no __qualname__): the documented name bound to the same object
            canonical = _documented_binding(domain, name, obj)
            if canonical is None:
                continue
        else:
            canonical = f"{where}.{qualname}"
        if canonical == name:
            continue
        found = domain.resolve_xref(
            env, node["refdoc"], app.builder, node["reftype"], canonical, node, contnode
        )
        if found is not None:
            return found
        found = domain.resolve_any_xref(env, node["refdoc"], app.builder, canonical, node, contnode)
        if found:
            return found[0][1]
    return None


def setup(app):
    app.connect("autodoc-process-docstring", _plain_bars)
    app.connect("missing-reference", _resolve_reexport)
