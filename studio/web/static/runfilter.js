/* Teach Studio page: which runs a filter keeps, and a run's tags as the lists show them.
 *
 * A filter is words, all of which must match (case does not matter): `tag:WORD` a tag of the
 * run, `task:WORD` its task ("grid", "continuous"), any other word its name, id, a tag or its task.
 */

import { runLabel, runTask } from "./chart.js";
import { el } from "./dom.js";
import { S } from "./state.js";

export function runTags(r) {
  const n = S.notes.get(r.id);
  return n ? n.tags : [];
}

export function runMatches(r, filter = S.runFilter) {
  const words = filter.toLowerCase().split(/\s+/).filter(Boolean);
  if (!words.length) return true;
  const tags = runTags(r).map((t) => t.toLowerCase());
  const task = r.damaged ? "" : runTask(r).toLowerCase();
  const name = `${r.id} ${r.damaged ? "" : runLabel(r)}`.toLowerCase();
  return words.every((w) => {
    if (w.startsWith("tag:")) return tags.some((t) => t.includes(w.slice(4)));
    if (w.startsWith("task:")) return task.includes(w.slice(5));
    return name.includes(w) || task.includes(w) || tags.some((t) => t.includes(w));
  });
}

/** A run's tags as small chips (nothing when it has none). */
export function tagChips(r) {
  const tags = runTags(r);
  return tags.length ? el("span", { class: "tags", testid: "run-tags" }, ...tags.map((t) => el("span", { class: "tag", text: t }))) : null;
}
