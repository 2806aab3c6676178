/* Teach Studio page: the 3D scene's iframe: its URL, whether it is this studio's, its legend, software WebGL. */

import { api } from "./api.js";
import { $, setProp, setText, showError } from "./dom.js";
import { S } from "./state.js";
import { resetTrainForm } from "./training.js";

// Without a GPU the scene is drawn at this device-pixel ratio (a quarter of the pixels at 0.5):
// a still scene then costs about 0.09 instead of 0.15 cores, a moving one far less, and that
// CPU goes to training instead. A browser with a GPU draws at its own ratio.
export const SOFTWARE_SCENE_DPR = 0.5;
export const SOFTWARE_RENDERERS = /swiftshader|llvmpipe|softpipe|software/i;

export async function loadConfig() {
  try {
    S.config = await api("GET", "/api/config");
    resetTrainForm(); // the learning package's defaults, the one definition
  } catch (e) {
    showError("scene-msg", `The 3D scene is unavailable: ${e.message}`);
    return;
  }
  setText("version", `v${S.config.version}`);
  const url = S.config.viser_url;
  if (!url) {
    showError("scene-msg", "This studio runs without a 3D scene (no viser URL configured).");
    return;
  }
  const src = sceneUrl(url);
  if (S.config.scene_instance && !(await sceneIsOurs(src, S.config.scene_instance))) {
    showError("scene-msg", `The 3D scene at ${new URL(src).host} does not belong to this studio (another studio or program answers there); restart this studio so that it starts its own scene.`);
    return;
  }
  $("scene").src = S.softwareScene ? withSceneDpr(src, SOFTWARE_SCENE_DPR) : src;
  setProp("scene-note", "hidden", !S.softwareScene);
  showSceneLegend(S.config.scene_colors || {});
}

/** The scene's legend, in the scene's own colours (served by /api/config, defined once). */
function showSceneLegend(colors) {
  for (const sw of $("scene-legend").querySelectorAll("[data-color]")) {
    const rgb = colors[sw.dataset.color];
    if (rgb) sw.style.color = `rgb(${rgb.join(",")})`;
  }
  setProp("scene-legend", "hidden", false);
}

/**
 * Whether this browser draws WebGL in software (no GPU: SwiftShader, llvmpipe). There every
 * frame of the scene is drawn by the CPU that trains, about 0.1 s of it per full-size frame.
 */
export function softwareWebGL() {
  try {
    const canvas = document.createElement("canvas");
    const gl = canvas.getContext("webgl2") || canvas.getContext("webgl");
    if (!gl) return false;
    const info = gl.getExtension("WEBGL_debug_renderer_info");
    const renderer = String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
    const lose = gl.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
    return SOFTWARE_RENDERERS.test(renderer);
  } catch (e) {
    return false;
  }
}

/** The scene URL asking viser's client to draw at a fixed device-pixel ratio. */
function withSceneDpr(src, dpr) {
  const u = new URL(src);
  u.searchParams.set("fixedDpr", String(dpr));
  return u.toString();
}

/** Whether the scene server at `src` is this studio's: it answers our instance id. */
async function sceneIsOurs(src, instance) {
  const u = new URL(src);
  u.pathname = "/studio-instance";
  u.hash = "";
  try {
    const r = await fetch(u.toString(), { cache: "no-store" });
    if (!r.ok) return false;
    const body = await r.json();
    return body.instance === instance;
  } catch (e) {
    return false;
  }
}

/**
 * The scene's URL, moved to another site when both servers are on this machine's loopback.
 *
 * Pages on one site share a renderer process and its main thread in Chromium, so a busy 3D scene
 * (software WebGL, a fast live stream) would delay the page's own work: curves, buttons, lists.
 * 127.0.0.1 and localhost are different sites, so swapping one for the other gives the scene its
 * own process. A loopback scene seen from a page on another machine (a studio serving 0.0.0.0)
 * is reached at the page's host. Any other host is left alone.
 */
function sceneUrl(url) {
  const u = new URL(url, location.href);
  const loopback = ["127.0.0.1", "localhost"];
  if (loopback.includes(u.hostname) && u.hostname === location.hostname) {
    u.hostname = u.hostname === "localhost" ? "127.0.0.1" : "localhost";
  } else if (loopback.includes(u.hostname) && !loopback.includes(location.hostname)) {
    u.hostname = location.hostname; // a studio on 0.0.0.0 opened from another machine
  }
  return u.toString();
}
