/* Teach Studio page: the boxes placed for the next run (the train form's "Add obstacle"): drawn in
 * the scene with a handle each to drag them, sized here, sent with the run. */

import { api } from "./api.js";
import { $, el, showError } from "./dom.js";

/** How often the list reads where the scene's handles stand while boxes are placed (ms). */
const POLL_MS = 1000;

let boxes = [];
let polling = null;

/** The boxes placed for the next run, as the API takes them ({centre, size} in metres). */
export function placedObstacles() { return boxes.map((b) => ({ centre: [...b.centre], size: [...b.size] })); }

/** Read the boxes where the scene's handles stand now (a drag moves them there). */
export async function refreshObstacles() {
  try {
    const data = await api("GET", "/api/scene/obstacles");
    boxes = data.obstacles || [];
  } catch { return; } // no scene (or offline): the list keeps what it had
  renderObstacles();
}

/** Ask the scene for ``next`` (the boxes; none: one more, beside the robot drawn), and list
 * what it placed; a refusal is said in one sentence under the list. */
async function place(next) {
  showError("obstacle-error", null);
  try {
    const data = next === undefined
      ? await api("POST", "/api/scene/obstacles")
      : await api("PUT", "/api/scene/obstacles", { obstacles: next });
    boxes = data.obstacles || [];
  } catch (e) {
    showError("obstacle-error", e.message || String(e));
  }
  renderObstacles();
}

/** "Add obstacle": one more box, 15 cm a side as the scene shows it, beside the robot drawn. */
export function addObstacle() { return place(); }

const fmt = (v) => (Math.round(v * 1000) / 1000).toString();

function renderObstacles() {
  const list = $("train-obstacles");
  if (!boxes.length) {
    list.replaceChildren(el("span", { class: "muted", text: "none" }));
  } else {
    list.replaceChildren(...boxes.map((box, i) => {
      const sizes = box.size.map((s, k) => el("input", {
        type: "number", step: "0.01", min: "0.01", value: fmt(s),
        title: `full size along ${"xyz"[k]} (m)`, testid: `obstacle-${i}-size-${k}`,
        onchange: (ev) => {
          const next = placedObstacles();
          next[i].size[k] = Number(ev.target.value);
          place(next);
        },
      }));
      const remove = el("button", {
        type: "button", text: "×", title: "remove this box", testid: `obstacle-${i}-remove`,
        onclick: () => place(placedObstacles().filter((_, k) => k !== i)),
      });
      return el("div", { class: "obstacle-row", testid: "obstacle-row" },
        el("span", { testid: `obstacle-${i}-centre`, text: `box ${i + 1} at (${box.centre.map(fmt).join(", ")}) m, size` }),
        ...sizes,
        remove);
    }));
  }
  if (boxes.length && polling === null) polling = setInterval(refreshObstacles, POLL_MS);
  if (!boxes.length && polling !== null) { clearInterval(polling); polling = null; }
}
