"""Pages of the documentation site written from the family specs at every build."""

from __future__ import annotations

import json


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
    }


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
