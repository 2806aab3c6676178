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


# The page's one state (static/state.js): every field declared once, with a comment; modules write
# declared fields only, announce changes through state.js (never a DOM event of their own), and put
# nothing on `window`. state.js also seals `S`, so a write the patterns below miss throws in the page.
DECLARED = re.compile(r"^  (\w+): .*?,\s*//\s*\S", re.M)
FIELD_LINE = re.compile(r"^  (\w+):", re.M)
WRITE = re.compile(r"\bS\.(\w+)\s*(?:=(?!=)|\+=|-=|\*=|/=|\+\+|--|\|\|=|&&=|\?\?=)")
NAMED = re.compile(r"(?<![.\w])(?:set|listen)\(\s*[\"'](\w+)[\"']")
WINDOW_WRITE = re.compile(
    r"\bwindow\.\w+\s*=(?!=)|Object\.(?:assign|defineProperty|defineProperties)\(\s*window\b|\bglobalThis\.\w+\s*=(?!=)"
)
OWN_EVENT = re.compile(r"\bnew\s+CustomEvent\b|addEventListener\(\s*[\"']studio:")


def declared_fields() -> dict[str, bool]:
    """state.js's fields of ``S``, each with whether its line carries a comment."""
    text = (STATIC_DIR / "state.js").read_text()
    body = text[text.index("Object.seal({") : text.index("\n});")]
    commented = set(DECLARED.findall(body))
    return {name: name in commented for name in FIELD_LINE.findall(body)}


def undeclared_writes(modules: dict[str, str], fields: set[str]) -> list[str]:
    """``path: S.field`` for every write (or set/listen) of a field ``fields`` does not hold."""
    found = []
    for path, text in modules.items():
        for name in WRITE.findall(text) + NAMED.findall(text):
            if name not in fields:
                found.append(f"{path}: S.{name}")
    return sorted(set(found))


def test_every_field_of_the_page_state_is_declared_once_with_a_comment():
    fields = declared_fields()
    assert len(fields) >= 20
    assert not [name for name, commented in fields.items() if not commented], (
        "a field without a comment"
    )
    text = (STATIC_DIR / "state.js").read_text()
    assert len(FIELD_LINE.findall(text[text.index("Object.seal({") :].split("\n});")[0])) == len(
        fields
    )
    assert "Object.seal({" in text  # an undeclared write throws in the page, too


def test_no_module_writes_a_field_state_js_does_not_declare():
    modules = page_modules()
    fields = set(declared_fields())
    assert undeclared_writes(modules, fields) == []
    # the check sees a write it should refuse, in each form a module could write it
    for line in ("S.chartZoomed = true;", "S.count += 1;", "S.count++;", 'set("gone", 1);'):
        assert undeclared_writes({"/static/x.js": line}, fields), line
    assert not undeclared_writes({"/static/x.js": "if (S.runs === x) S.runs = [];"}, fields)


def test_the_page_puts_nothing_on_window_and_announces_through_state_js():
    for path, text in page_modules().items():
        assert not WINDOW_WRITE.search(text), f"{path} puts a global on window"
        assert not OWN_EVENT.search(text), f"{path} announces with a DOM event of its own"
    assert WINDOW_WRITE.search("window.studio = S;")
    assert WINDOW_WRITE.search("Object.assign(window, { api });")
    assert OWN_EVENT.search('document.dispatchEvent(new CustomEvent("studio:robot"));')
