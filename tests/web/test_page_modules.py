"""The page's scripts: ES modules with no build step, each small, all served by the studio as JavaScript.

The page loads its modules from index.html, and they import one another; a module missing from the
static folder, served with a type other than JavaScript (a browser then refuses to run it), or
fetched from another host would leave the page dead. Every page script stays under 600 lines.
"""

from __future__ import annotations

import re

from studio.web._app import STATIC_DIR

MAX_LINES = 600
SCRIPT = re.compile(r'<script\b[^>]*\bsrc="(/static/[^"]+\.js)"[^>]*>')
MODULE = re.compile(r'<script\b[^>]*\btype="module"[^>]*\bsrc="(/static/[^"]+\.js)"')
IMPORT = re.compile(r'^\s*import\s+(?:[^"\']*\bfrom\s+)?["\']([^"\']+)["\']', re.M)


def page_modules() -> dict[str, str]:
    """Every module the page runs, by its URL path, following imports from index.html."""
    html = (STATIC_DIR / "index.html").read_text()
    todo = MODULE.findall(html)
    found: dict[str, str] = {}
    while todo:
        path = todo.pop()
        if path in found:
            continue
        text = (STATIC_DIR / path.removeprefix("/static/")).read_text()
        found[path] = text
        for target in IMPORT.findall(text):
            assert target.startswith("./"), f"{path} imports {target}: only the studio's own files"
            todo.append(path.rsplit("/", 1)[0] + "/" + target.removeprefix("./"))
    return found


def test_the_page_runs_as_modules_each_under_600_lines():
    html = (STATIC_DIR / "index.html").read_text()
    modules = page_modules()
    own = {s for s in SCRIPT.findall(html) if "/vendor/" not in s}
    assert own <= set(modules), "the page's own scripts are ES modules"
    assert "/static/main.js" in modules and len(modules) >= 8
    for path, text in modules.items():
        assert text.count("\n") <= MAX_LINES, f"{path} has {text.count(chr(10))} lines"
    # every page script in the folder is one the page loads: nothing left behind
    on_disk = {f"/static/{p.name}" for p in STATIC_DIR.glob("*.js")}
    assert on_disk == set(modules)


def test_every_module_is_served_as_javascript(client):
    for path, text in page_modules().items():
        r = client.get(path)
        assert r.status_code == 200, path
        assert r.text == text
        assert "javascript" in r.headers["content-type"], (path, r.headers["content-type"])
