/* Teach Studio page: talking to the studio's API (docs/api.md): requests, their one-sentence errors, sending in turn, downloads. */

import { showError } from "./dom.js";
import { S } from "./state.js";

export class ApiError extends Error {}

export async function api(method, path, body) {
  const opts = { method, headers: {} };
  if (body instanceof FormData) {
    opts.body = body;
  } else if (body !== undefined) {
    opts.headers["Content-Type"] = "application/json";
    opts.body = JSON.stringify(body);
  }
  let resp;
  try {
    resp = await fetch(path, opts);
  } catch (e) {
    throw new ApiError("The studio server is not reachable; check that `studio serve` is still running.");
  }
  if (resp.status === 204) return null;
  const text = await resp.text();
  let data = null;
  try { data = text ? JSON.parse(text) : null; } catch (e) { data = null; }
  if (!resp.ok) {
    const err = new ApiError(detailOf(data, resp, text));
    err.data = data; // e.g. a refused form: {detail, problems, by_field}
    throw err;
  }
  return data;
}

function detailOf(data, resp, text) {
  if (data && data.detail !== undefined) {
    const d = data.detail;
    if (typeof d === "string") return d;
    if (Array.isArray(d)) return d.map((x) => (x && x.msg) || JSON.stringify(x)).join("; ");
    return JSON.stringify(d);
  }
  if (resp.status === 413) return "The file is larger than the upload limit.";
  if (resp.status === 404) return `Not found (${resp.url.replace(location.origin, "")}): this server does not offer that yet.`;
  return `The server answered ${resp.status} ${resp.statusText}${text ? ": " + text.slice(0, 200) : ""}.`;
}

/** Run an action, showing its error (or clearing the old one) next to the control. */
export async function guarded(errId, fn, button) {
  showError(errId, null);
  if (button) button.disabled = true;
  try {
    return await fn();
  } catch (e) {
    showError(errId, e);
    if (!(e instanceof ApiError)) console.error(e);
    return undefined;
  } finally {
    if (button) button.disabled = false;
  }
}

/** A queue of actions that must reach the server one at a time, in the order the user made them
 * (a seek, then play). Returns the function that queues one: called with ``fn``, it runs ``fn``
 * once everything queued before it has settled (a failed one too) and returns ``fn``'s promise. */
export function inTurn() {
  let last = Promise.resolve();
  return (fn) => {
    const run = last.then(fn);
    last = run.catch(() => {});
    return run;
  };
}

/** Fetch a file and save it, so that a refusal (409, 404) shows up as a message, not a page.
 * Returns the refusal's body (``{detail, reason}``) when the studio refused, else null;
 * ``onSaved`` (optional) is given the response of a file saved (its headers). */
export async function download(url, fallbackName, errId, onSaved) {
  showError(errId, null);
  let resp;
  try {
    resp = await fetch(url);
  } catch (e) {
    showError(errId, "The studio server is not reachable.");
    return { detail: "The studio server is not reachable." };
  }
  if (!resp.ok) {
    const text = await resp.text();
    let data = null;
    try { data = JSON.parse(text); } catch (e) { data = null; }
    showError(errId, detailOf(data, resp, text));
    return data || { detail: detailOf(data, resp, text) };
  }
  const blob = await resp.blob();
  const cd = resp.headers.get("Content-Disposition") || "";
  const m = /filename\*?=(?:UTF-8'')?"?([^";]+)"?/i.exec(cd);
  const name = m ? decodeURIComponent(m[1]) : fallbackName;
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.appendChild(a);
  a.click();
  setTimeout(() => { URL.revokeObjectURL(a.href); a.remove(); }, 1000);
  if (onSaved) onSaved(resp);
  return null;
}

/** Upload the file chosen in ``input`` to ``path`` and hand the studio's answer to ``then``
 * (a file over the upload limit is refused here); errors show at ``errId``. */
export async function uploadChosen(input, path, errId, then) {
  const f = input.files[0];
  if (!f) return;
  await guarded(errId, async () => {
    checkUploadSize(f);
    const fd = new FormData();
    fd.append("file", f, f.name);
    await then(await api("POST", path, fd));
  });
  input.value = "";
}

function checkUploadSize(f) {
  const limit = S.config && S.config.upload_limit_bytes;
  if (limit && f.size > limit) {
    throw new ApiError(`${f.name} is ${(f.size / 1e6).toFixed(1)} MB, over the ${(limit / 1e6).toFixed(0)} MB upload limit.`);
  }
}
