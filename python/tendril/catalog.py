"""The library's index: catalog.json and an HTML contact sheet (docs/batch.md).

`write_catalog(out_dir)` lists every variant directory under `<out_dir>/variants/` whose
variant.json and outputs verify, and writes `catalog.json` and `index.html` atomically.

    python -m tendril.catalog DIR        # rewrite DIR/catalog.json and DIR/index.html
"""

from __future__ import annotations

import html
import json
import sys
from pathlib import Path

from .sweep import write_atomic

CATALOG_FORMAT = "tendril-catalog"


def collect(out_dir) -> list:
    from .batch import read_variant, variants_dir

    vroot = variants_dir(out_dir)
    found = []
    if vroot.is_dir():
        for d in sorted(vroot.iterdir()):
            if d.name.startswith(".") or not d.is_dir():
                continue
            info = read_variant(d)
            if info is None:
                continue
            found.append({k: info[k] for k in ("key", "index", "name", "parameters", "outputs", "triangles", "steps",
                                                "state_hash", "timings", "warnings", "growth_problems")})
    found.sort(key=lambda v: (v["index"], v["name"], v["key"]))
    return found


def write_catalog(out_dir) -> dict:
    """Writes <out_dir>/catalog.json and <out_dir>/index.html; returns {"count": n}."""
    from . import version

    out = Path(out_dir)
    variants = collect(out)
    doc = {"format": CATALOG_FORMAT, "version": 1, "tendril": version(), "count": len(variants), "variants": variants}
    write_atomic(out / "catalog.json", json.dumps(doc, indent=1, sort_keys=True).encode() + b"\n")
    write_atomic(out / "index.html", contact_sheet(variants, out.resolve().name).encode())
    return {"count": len(variants)}


def _value(v) -> str:
    return html.escape(v if isinstance(v, str) else json.dumps(v))


def contact_sheet(variants: list, title: str) -> str:
    e = html.escape
    cards = []
    for v in variants:
        base = f"variants/{v['key']}/"
        thumb = (f'<a href="{base}preview.png"><img src="{base}preview.png" alt="{e(v["name"])}" loading="lazy"></a>'
                 if "preview.png" in v["outputs"] else '<div class="noimg">no preview</div>')
        params = "".join(f"<tr><th>{e(k)}</th><td>{_value(x)}</td></tr>" for k, x in v["parameters"].items())
        tris = " / ".join(f"{t:,}" for t in v["triangles"])
        levels = "LOD0" if len(v["triangles"]) == 1 else f"LOD0–{len(v['triangles']) - 1}"
        links = " ".join(f'<a href="{base}{e(f)}">{e(f)}</a>' for f in v["outputs"] if f != "preview.png")
        flag = ' <span class="warn" title="{}">⚠</span>'.format(e("; ".join(v["growth_problems"]))) if v["growth_problems"] else ""
        cards.append(f'<div class="card">{thumb}<div class="name">{e(v["name"])}{flag}</div>'
                     f'<table>{params}<tr><th>steps</th><td>{v["steps"]}</td></tr></table>'
                     f'<div class="tris">triangles ({levels}): {tris}</div>'
                     f'<div class="links">{links} <a href="{base}variant.json">variant.json</a></div></div>')
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>{e(title)}: {len(variants)} variants</title>
<style>
body {{ font: 13px system-ui, sans-serif; margin: 16px; background: #f4f4f2; color: #222; }}
h1 {{ font-size: 18px; margin: 0 0 12px; }}
.grid {{ display: grid; grid-template-columns: repeat(auto-fill, minmax(220px, 1fr)); gap: 12px; }}
.card {{ background: #fff; border-radius: 6px; padding: 8px; box-shadow: 0 1px 3px #0002; }}
.card img, .noimg {{ width: 100%; aspect-ratio: 4 / 3; object-fit: cover; border-radius: 4px; background: #ddd; display: block; }}
.noimg {{ display: flex; align-items: center; justify-content: center; color: #888; }}
.name {{ font-weight: 600; margin: 6px 0 4px; }}
table {{ border-collapse: collapse; width: 100%; }}
th {{ text-align: left; font-weight: normal; color: #666; padding-right: 6px; white-space: nowrap; }}
td {{ text-align: right; font-variant-numeric: tabular-nums; word-break: break-all; }}
div.tris {{ margin-top: 2px; color: #444; font-variant-numeric: tabular-nums; }}
.links {{ margin-top: 4px; }} .links a {{ margin-right: 6px; }} .warn {{ color: #c60; }}
</style></head>
<body><h1>{e(title)}: {len(variants)} variants</h1>
<div class="grid">
{chr(10).join(cards)}
</div></body></html>
"""


def main(argv=None) -> int:
    from . import Error

    argv = sys.argv[1:] if argv is None else argv
    if len(argv) != 1:
        print("usage: python -m tendril.catalog DIR", file=sys.stderr)
        return 2
    try:
        n = write_catalog(argv[0])["count"]
    except (Error, OSError) as e:
        print(f"tendril: error: {e}", file=sys.stderr)
        return 2
    print(f"{n} variants in {Path(argv[0]) / 'catalog.json'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
