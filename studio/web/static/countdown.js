/* Teach Studio page: the countdown before a recording of the camera or the hand guide, or a take. */

import { $, setProp, setText } from "./dom.js";
import { S } from "./state.js";

let countdownRun = null; // {cancel()} while a countdown runs

/**
 * Count down before a recording of the camera or the hand guide starts (before a take, whatever
 * the source: ``always``), so the user can get into place. Resolves true to start, false when
 * cancelled (the same button pressed again, or Escape during a take's countdown).
 */
export function recordCountdown(always = false, cancelHint = "press Record again to cancel") {
  if (countdownRun) { countdownRun.cancel(); return Promise.resolve(false); }
  const kind = S.source && S.source.kind;
  const seconds = Math.max(0, Math.min(10, Math.round(Number($("capture-countdown").value) || 0)));
  if ((!always && !["camera", "hand"].includes(kind)) || !seconds) return Promise.resolve(true);
  const left = $("capture-countdown-left");
  return new Promise((resolve) => {
    let n = seconds;
    const finish = (go) => {
      clearInterval(timer);
      countdownRun = null;
      setProp(left, "hidden", true);
      setText(left, "");
      resolve(go);
    };
    const show = () => setText(left, `Recording in ${n} s (${cancelHint})`);
    const timer = setInterval(() => {
      n -= 1;
      if (n <= 0) finish(true);
      else show();
    }, 1000);
    countdownRun = { cancel: () => finish(false) };
    show();
    setProp(left, "hidden", false);
  });
}
