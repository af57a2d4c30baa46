"""Pages of the documentation site written from the family specs at every build, and the
README's generated block.

``python docs/generated.py --write-readme`` rewrites the README's block between
``<!-- families:begin -->`` and ``<!-- families:end -->`` in place (``--check-readme`` exits 1
when it is stale; ``tests/orchestration/test_readme.py`` fails then too).
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
BEGIN = "<!-- families:begin -->"
END = "<!-- families:end -->"


def thesis_order(family: object) -> tuple[int, bool, str]:
    """Sort key: the family's chapter as its title names it ("(chapter 3)", "(§6.2)"), a
    chapter's certification family (the SOP) after its main one, then the kind: chapters
    2, 3, 4, 5, SOP, 6. A title naming no chapter sorts last."""
    import re

    title = str(getattr(family, "title", ""))
    found = re.search(r"chapter (\d+)|§(\d+)", title)
    chapter = int(found.group(1) or found.group(2)) if found else 99
    return chapter, "certification" in title, str(getattr(family, "kind", ""))


def generated_pages() -> dict[str, str]:
    """The pages written from the family specs and the schema folder at every build (not kept
    in git): ``kinds.md`` (one row per family in the thesis's order: kind, problem type,
    payload, bounds, methods, studies) and ``schemas.md`` (every shipped schema). A new family appears in both without
    an edit to any page."""
    from taopt import schemas
    from taopt.orchestration.pipeline import available_methods
    from taopt.registry import families
    from taopt.result import payload_schemas

    rows = []
    for family in sorted(families(), key=thesis_order):
        bounds = ", ".join(
            f"`{name}` ({'valid' if b.valid else 'as printed'}, {b.side})"
            for name, b in family.bounds.items()
        )
        studies = ", ".join(f"`taopt study {s.name}`" for s in family.studies) or "—"
        rows.append(
            f"| `{family.kind}` | {family.title} | `{family.problem_type.__name__}` | "
            f"`{family.payload.__name__}` | {bounds} | "
            f"{', '.join(available_methods(family.problem_type))} | {studies} |"
        )
    kinds = "\n".join(
        [
            "# Problem families and their file kinds",
            "",
            "Generated from the family specs (`taopt.registry.families()`; the same list as "
            "`taopt kinds`). Each kind's schema is on [](schemas.md) and a small example ships in "
            "`taopt/data/examples/<kind>.json`.",
            "",
            "| kind | family | problem | payload | bounds | methods | studies |",
            "|---|---|---|---|---|---|---|",
            *rows,
            "",
            "## Methods by problem type",
            "",
            "The table the README shows (the same function writes both, "
            "`python docs/generated.py --write-readme`):",
            "",
            families_table(),
            *[
                line
                for family in sorted(families(), key=thesis_order)
                for line in (
                    f"## `{family.kind}`",
                    "",
                    f"{family.title}. Example `taopt/data/examples/{family.kind}.json`:",
                    "",
                    f"```{{literalinclude}} ../taopt/data/examples/{family.kind}.json",
                    ":language: json",
                    "```",
                    "",
                )
            ],
        ]
    )
    parts = [
        "# JSON Schemas",
        "",
        "The schemas (JSON Schema draft 2020-12) that every file is checked against before any "
        "object is built; [](file-formats.md) explains the kinds field by field and [](kinds.md) "
        "lists the families. They ship with the package in `taopt/schemas/`, and "
        "`taopt.schemas.validate` applies them. This page is generated from that folder.",
        "",
    ]
    for kind in schemas.kinds():
        parts += [
            f"(schema-{kind})=",
            f"## `{kind}`",
            "",
            f"`taopt/schemas/{kind}.schema.json`:",
            "",
            f"```{{literalinclude}} ../taopt/schemas/{kind}.schema.json",
            ":language: json",
            "```",
            "",
        ]
    payloads = payload_schemas()
    parts += [
        "(schema-payloads)=",
        "## Payload kinds of `solution`",
        "",
        "`solution.schema.json` lists no payload kind: each payload type declares its schema "
        "where it is registered (`taopt.result.register_payload`), and "
        "`taopt.schemas.schema('solution')` adds it as `$defs/<payload_kind>` with the rule "
        "that a solution of that `payload_kind` carries such a payload. Today's:",
        "",
    ]
    for name, payload_schema in payloads.items():
        parts += [f"### `{name}`", "", "```json", json.dumps(payload_schema, indent=2), "```", ""]
    return {
        "kinds.md": kinds,
        "schemas.md": "\n".join(parts),
        "api/index.md": api_index(),
        "_includes/family-kinds.md": family_kinds_table(),
        "_includes/payload-kinds.md": payload_kinds_table(),
    }


def _registered(problem_type: type, peers: bool) -> list[str]:
    """Every method registered for ``problem_type``, exact first (the order of
    :func:`~taopt.orchestration.pipeline.available_methods`), peers only or none of them;
    whatever is installed on the machine that writes the table."""
    import taopt.orchestration.pipeline  # noqa: F401  (imports every method package)
    from taopt.registry import CATEGORIES, methods

    found = [
        spec
        for spec in methods(problem_type).values()
        if (spec.category == "peer") == peers and spec.category != "relaxation"
    ]
    found.sort(key=lambda spec: CATEGORIES.index(spec.category))
    return [spec.name for spec in found]


def families_table() -> str:
    """The README's table of the problem families, one row per family spec in the thesis's
    order: problem type, family (its spec's title), the methods (non-peer, exact first, as
    :func:`~taopt.orchestration.pipeline.available_methods` lists them after ``pip install
    .``), the peers (with ``taopt[peers]``) and its studies."""
    from taopt.registry import families

    rows = [
        "| problem type | family | methods | peers | study |",
        "|---|---|---|---|---|",
    ]
    for family in sorted(families(), key=thesis_order):
        peers = ", ".join(_registered(family.problem_type, peers=True)) or "—"
        studies = ", ".join(f"`taopt study {s.name}`" for s in family.studies) or "—"
        rows.append(
            f"| `{family.problem_type.__name__}` | {family.title} | "
            f"{', '.join(_registered(family.problem_type, peers=False))} | {peers} | {studies} |"
        )
    return "\n".join(rows) + "\n"


def readme_block() -> str:
    """The README's generated block, markers included."""
    return (
        f"{BEGIN}\n<!-- written by `python docs/generated.py --write-readme` from the family "
        f"specs; do not edit by hand -->\n\n{families_table()}\n{END}"
    )


def readme_with_block(text: str) -> str:
    """``text`` (the README) with its generated block replaced by :func:`readme_block`."""
    pattern = re.compile(re.escape(BEGIN) + r".*?" + re.escape(END), re.S)
    if not pattern.search(text):
        raise SystemExit(f"README.md has no {BEGIN} ... {END} block")
    return pattern.sub(lambda _: readme_block(), text, count=1)


def payload_kinds_table() -> str:
    """docs/file-formats.md's table of the ``payload_kind`` values of a solution: every
    registered payload and the problem kinds whose solutions carry it."""
    from taopt.registry import families
    from taopt.result import payload_schemas

    rows = ["| `payload_kind` | solutions of |", "|---|---|"]
    for name in payload_schemas():
        kinds = sorted(
            f"`{f.kind}`" for f in families() if getattr(f.payload, "payload_kind", "") == name
        )
        rows.append(f"| `{name}` | {', '.join(kinds)} |")
    return "\n".join(rows) + "\n"


def family_kinds_table() -> str:
    """docs/file-formats.md's table of the problem kinds, one row per family spec (included
    there, so a new family's kind is listed without an edit; its links are resolved from
    the including page)."""
    from taopt.registry import families

    rows = [
        "| kind | schema | read by | written by |",
        "|---|---|---|---|",
    ]
    for family in sorted(families(), key=lambda f: f.kind):
        name = family.problem_type.__name__
        readers = [f"`{name}.load`", "`taopt solve`"]
        rows.append(
            f"| `{family.kind}` | [`{family.kind}.schema.json`](schemas.md#{family.kind}) | "
            f"{', '.join(readers)} | `{name}.save` |"
        )
    return "\n".join(rows) + "\n"


def api_index() -> str:
    """The API reference's index: every public module and package of taopt, found with
    pkgutil (a new family's package is documented without an edit)."""
    import pkgutil

    import taopt

    names = sorted(
        f"taopt.{module.name}"
        for module in pkgutil.iter_modules(taopt.__path__)
        if not module.name.startswith("_")
    )
    names = sorted({*names, "taopt.models", "taopt.heuristics"})
    return "\n".join(
        [
            "# API reference",
            "",
            "Generated from the docstrings (numpydoc). The top-level package {mod}`taopt` holds "
            "the entry",
            "points used on every page of this site; each package below documents its own "
            "modules (this list is generated from the package, docs/generated.py).",
            "",
            "```{toctree}",
            ":maxdepth: 1",
            "",
            "taopt",
            "```",
            "",
            "```{eval-rst}",
            ".. autosummary::",
            "   :toctree: generated",
            "   :recursive:",
            "",
            *[f"   {name}" for name in names],
            "```",
            "",
        ]
    )


def main(argv: list[str]) -> int:
    """``--write-readme``: rewrite the README's block in place; ``--check-readme``: 1 if stale."""
    sys.path.insert(0, str(ROOT))
    text = README.read_text()
    new = readme_with_block(text)
    if "--write-readme" in argv:
        if new != text:
            README.write_text(new)
        print("README.md: block", "rewritten" if new != text else "already current")
        return 0
    if "--check-readme" in argv:
        print("README.md: block", "stale" if new != text else "current")
        return int(new != text)
    print("usage: python docs/generated.py --write-readme | --check-readme")
    return 2


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
