// The Sphero Edu JavaScript API as programs see it: names, arguments and return shapes as
// Sphero documents them. Each call hands plain numbers and strings to droidctl's natives
// (`__call`, `__read`, `__on`), which do the work on its own clock (src/edu/api.rs).
//
// This script is one function expression: droidctl calls it with the natives, and it puts
// the API on the global object. The natives stay in its closure, so a program cannot name
// them and skip the checks here (issue 37); they check their arguments again all the same.
(function (__call, __read, __on) {
"use strict";
const EventType = Object.freeze({
  onCollision: "onCollision", onFreefall: "onFreefall", onLanding: "onLanding",
  onGyroMax: "onGyroMax", onCharging: "onCharging", onNotCharging: "onNotCharging",
  onIRMessage: "onIRMessage", onColor: "onColor",
});
const Stance = Object.freeze({ Bipod: "twolegs", Tripod: "threelegs" });
const MatrixRotation = Object.freeze({ Deg0: 0, Deg90: 90, Deg180: 180, Deg270: 270 });
const MatrixAnimationTransition = Object.freeze({ None: "none", Fade: "fade" });
// A number, or NaN (a symbol too, which `Number` would throw on without naming the call).
function __number(v) { return typeof v === "symbol" ? NaN : Number(v); }
function __num(v, what) {
  const n = __number(v);
  if (!Number.isFinite(n)) throw new TypeError(what + " must be a number, not " + String(v).slice(0, 40));
  return n;
}
function __rgb(c, what) {
  if (c === null || typeof c !== "object") throw new TypeError(what + " must be a color like { r: 255, g: 0, b: 0 }");
  const ch = (v) => Math.max(0, Math.min(255, Math.round(__number(v) || 0)));
  return [ch(c.r), ch(c.g), ch(c.b)];
}
function __xy(p, what) {
  if (p === null || typeof p !== "object") throw new TypeError(what + " must be a point like { x: 0, y: 0 }");
  return [__num(p.x, what + ".x"), __num(p.y, what + ".y")];
}
function __obj(keys, a) { if (!a) return null; const o = {}; keys.forEach((k, i) => { o[k] = a[i]; }); return o; }
function roll(heading, speed, duration) { return __call("roll", __num(heading, "roll: heading"), __num(speed, "roll: speed"), __num(duration, "roll: duration")); }
function rollDistance(heading, speed, distance) { return __call("rollDistance", __num(heading, "rollDistance: heading"), __num(speed, "rollDistance: speed"), __num(distance, "rollDistance: distance")); }
function rollToDistance(heading, speed, distance) { return __call("rollToDistance", __num(heading, "rollToDistance: heading"), __num(speed, "rollToDistance: speed"), __num(distance, "rollToDistance: distance")); }
function driveToDistance(heading, speed, distance) { return __call("driveToDistance", __num(heading, "driveToDistance: heading"), __num(speed, "driveToDistance: speed"), __num(distance, "driveToDistance: distance")); }
function setSpeed(speed) { return __call("setSpeed", __num(speed, "setSpeed: speed")); }
function setHeading(heading) { return __call("setHeading", __num(heading, "setHeading: heading")); }
function stopRoll(heading) { return heading === undefined ? __call("stopRoll") : __call("stopRoll", __num(heading, "stopRoll: heading")); }
function spin(degrees, duration) { return __call("spin", __num(degrees, "spin: degrees"), __num(duration, "spin: duration")); }
function rawMotor(left, right, duration) { return __call("rawMotor", __num(left, "rawMotor: left"), __num(right, "rawMotor: right"), duration === undefined ? -1 : __num(duration, "rawMotor: duration")); }
function setStabilization(on) { return __call("setStabilization", on ? 1 : 0); }
function resetAim() { return __call("resetAim"); }
function delay(seconds) { return __call("delay", __num(seconds, "delay: seconds")); }
function exitProgram() { return __call("exitProgram"); }
function setMainLed(color) { return __call("setMainLed", ...__rgb(color, "setMainLed: color")); }
function setFrontLed(color) { return __call("setFrontLed", ...__rgb(color, "setFrontLed: color")); }
function setBackLed(color) {
  if (typeof color === "number") return __call("setBackLedBrightness", __num(color, "setBackLed: brightness"));
  return __call("setBackLed", ...__rgb(color, "setBackLed: color"));
}
function setLeftHeadlightLed(color) { return __call("setLeftHeadlightLed", ...__rgb(color, "setLeftHeadlightLed: color")); }
function setRightHeadlightLed(color) { return __call("setRightHeadlightLed", ...__rgb(color, "setRightHeadlightLed: color")); }
function setLeftLed(color) { return __call("setLeftLed", ...__rgb(color, "setLeftLed: color")); }
function setRightLed(color) { return __call("setRightLed", ...__rgb(color, "setRightLed: color")); }
function fade(from, to, duration) { return __call("fade", ...__rgb(from, "fade: fromColor"), ...__rgb(to, "fade: toColor"), __num(duration, "fade: duration")); }
function strobe(color, period, count) { return __call("strobe", ...__rgb(color, "strobe: color"), __num(period, "strobe: period"), __num(count, "strobe: count")); }
function setHoloProjectorLed(b) { return __call("setHoloProjectorLed", __num(b, "setHoloProjectorLed: brightness")); }
function setLogicDisplayLeds(b) { return __call("setLogicDisplayLeds", __num(b, "setLogicDisplayLeds: brightness")); }
function setDomeLeds(b) { return __call("setDomeLeds", __num(b, "setDomeLeds: brightness")); }
// Sphero Edu's BOLT+ screen pictures: no public description says what BOLT+ takes on the wire
// for them (sphero-unsw 0.1.13, the one description of BOLT+, draws its screen with BOLT's matrix
// commands only), so the call is refused in words rather than guessed (issue 41).
function setDisplayImage() { throw new TypeError("setDisplayImage(): what BOLT+ takes on the wire for a screen picture is not described anywhere public, so droidctl cannot send one; draw on its screen with setMatrixCharacter, drawMatrixPixel, drawMatrixLine, drawMatrixFill or registerMatrixAnimation"); }
function setMatrixCharacter(character, color) { return __call("setMatrixCharacter", String(character), ...__rgb(color, "setMatrixCharacter: color")); }
function scrollMatrixText(text, color, fps, wait) { return __call("scrollMatrixText", String(text), ...__rgb(color, "scrollMatrixText: color"), fps === undefined ? 10 : __num(fps, "scrollMatrixText: fps"), wait === false ? 0 : 1); }
function drawMatrixPixel(color, p) { return __call("drawMatrixPixel", ...__rgb(color, "drawMatrixPixel: color"), ...__xy(p, "drawMatrixPixel: point")); }
function drawMatrixLine(color, a, b) { return __call("drawMatrixLine", ...__rgb(color, "drawMatrixLine: color"), ...__xy(a, "drawMatrixLine: start"), ...__xy(b, "drawMatrixLine: end")); }
function drawMatrixFill(color, a, b) { return __call("drawMatrixFill", ...__rgb(color, "drawMatrixFill: color"), ...__xy(a, "drawMatrixFill: start"), ...__xy(b, "drawMatrixFill: end")); }
function clearMatrix() { return __call("clearMatrix"); }
function setMatrixRotation(degrees) { return __call("setMatrixRotation", __num(degrees, "setMatrixRotation: degrees")); }
let __animations = 0;
function registerMatrixAnimation(a) {
  const what = "registerMatrixAnimation";
  if (a === null || typeof a !== "object") throw new TypeError(what + " takes { frames, palette, fps, transition }");
  const frames = a.frames, palette = a.palette;
  if (!Array.isArray(frames) || frames.length < 1 || frames.length > 64) throw new RangeError(what + ": frames must be an array of 1 to 64 frames");
  if (!Array.isArray(palette) || palette.length < 1 || palette.length > 16) throw new RangeError(what + ": palette must be an array of 1 to 16 colors");
  const flat = [];
  frames.forEach((f, i) => {
    if (!Array.isArray(f) || f.length !== 8) throw new TypeError(what + ": frame " + i + " must be 8 rows");
    f.forEach((row, y) => {
      if (!Array.isArray(row) || row.length !== 8) throw new TypeError(what + ": frame " + i + " row " + y + " must be 8 palette indexes");
      row.forEach((v) => flat.push(__num(v, what + ": a pixel")));
    });
  });
  const colours = [];
  palette.forEach((c) => colours.push(...__rgb(c, what + ": a palette color")));
  const fade = a.transition === MatrixAnimationTransition.Fade ? 1 : 0;
  __call(what, a.fps === undefined ? 10 : __num(a.fps, what + ": fps"), fade, palette.length, ...colours, frames.length, ...flat);
  return __animations++;
}
function playMatrixAnimation(index, loop) { return __call("playMatrixAnimation", __num(index, "playMatrixAnimation: index"), loop === false ? 0 : 1); }
function pauseMatrixAnimation() { return __call("pauseMatrixAnimation"); }
function resumeMatrixAnimation() { return __call("resumeMatrixAnimation"); }
function speak(text, wait) { return __call("speak", String(text), wait ? 1 : 0); }
function playSound(sound, wait) { return __call("playSound", String(sound), wait ? 1 : 0); }
// Sphero Edu's sounds: `Sound.Category.Name.play(wait)`, `Sound.Category.play(wait)` (a
// random one of the category), `Sound.play(wait)` (any). Sphero publishes no list of the
// names, so any category and name is taken (two levels deep) and said as written.
function __sound(path, depth) {
  const play = (wait) => __call("playSound", path, wait ? 1 : 0);
  return new Proxy(Object.freeze({ play }), {
    get(target, key) {
      if (key === "play") return play;
      if (typeof key !== "string" || depth >= 2 || key === "then") return undefined;
      return __sound(path === "" ? key : path + "." + key, depth + 1);
    },
  });
}
const Sound = __sound("", 0);
function __text(v) {
  if (typeof v === "string") return v;
  if (v !== null && typeof v === "object") { try { return JSON.stringify(v); } catch (e) { return String(v); } }
  return typeof v === "symbol" ? v.toString() : String(v);
}
function buildString(...parts) { return parts.map(__text).join(""); }
const console = Object.freeze({ log: (...parts) => { __call("console.log", parts.map(__text).join(" ").slice(0, 900)); } });
// Timers on droidctl's clock: each waits with `delay`, so under --sim they take simulated time.
let __timer = 0;
const __timers = new Map();
function __arm(fn, ms, args, every) {
  if (typeof fn !== "function") throw new TypeError((every ? "setInterval" : "setTimeout") + ": needs a function to call");
  const id = ++__timer;
  const wait = Math.max(0, __number(ms) || 0) / 1000;
  __timers.set(id, true);
  const tick = async () => {
    await delay(wait);
    if (!__timers.has(id)) return;
    if (!every) __timers.delete(id);
    const r = fn(...args);
    if (every) { await r; tick(); }
    else await r;
  };
  tick();
  return id;
}
function setTimeout(fn, ms, ...args) { return __arm(fn, ms, args, false); }
function setInterval(fn, ms, ...args) { return __arm(fn, ms, args, true); }
function clearTimeout(id) { __timers.delete(id); }
function clearInterval(id) { __timers.delete(id); }
function playAnimation(animation) { return __call("playAnimation", __num(animation, "playAnimation: animation")); }
function setDomePosition(degrees) { return __call("setDomePosition", __num(degrees, "setDomePosition: degrees")); }
function setStance(stance) { return __call("setStance", stance === Stance.Bipod || stance === "bipod" ? 2 : 3); }
function setWaddle(on) { return __call("setWaddle", on ? 1 : 0); }
function calibrateCompass() { return __call("calibrateCompass"); }
function startIRBroadcast(near, far) { return __call("startIRBroadcast", __num(near, "startIRBroadcast: near"), __num(far, "startIRBroadcast: far")); }
function stopIRBroadcast() { return __call("stopIRBroadcast"); }
function startIRFollow(near, far) { return __call("startIRFollow", __num(near, "startIRFollow: near"), __num(far, "startIRFollow: far")); }
function stopIRFollow() { return __call("stopIRFollow"); }
function startIREvade(near, far) { return __call("startIREvade", __num(near, "startIREvade: near"), __num(far, "startIREvade: far")); }
function stopIREvade() { return __call("stopIREvade"); }
function sendIRMessage(channel, intensity) { return __call("sendIRMessage", __num(channel, "sendIRMessage: channel"), __num(intensity, "sendIRMessage: intensity")); }
function listenForIRMessage(channels) {
  const list = Array.isArray(channels) ? channels : [channels];
  if (list.length > 64) throw new RangeError("listenForIRMessage: at most 64 channels, not " + list.length);
  return __call("listenForIRMessage", ...list.map((c) => __num(c, "listenForIRMessage: channel")));
}
function getLocation() { return __obj(["x", "y"], __read("getLocation")); }
function getVelocity() { return __obj(["x", "y"], __read("getVelocity")); }
function getSpeed() { return __read("getSpeed"); }
function getHeading() { return __read("getHeading"); }
function getOrientation() { return __obj(["pitch", "roll", "yaw"], __read("getOrientation")); }
function getAcceleration() { return __obj(["x", "y", "z"], __read("getAcceleration")); }
function getVerticalAcceleration() { return __read("getVerticalAcceleration"); }
function getGyroscope() { return __obj(["pitch", "roll", "yaw"], __read("getGyroscope")); }
function getDistance() { return __read("getDistance"); }
function getElapsedTime() { return __read("getElapsedTime"); }
function getLuminosity() { return __read("getLuminosity"); }
function getColor() { return __obj(["r", "g", "b"], __read("getColor")); }
function getCompassDirection() { return __read("getCompassDirection"); }
function getBatteryVoltage() { return __read("getBatteryVoltage"); }
function getMainLed() { return __obj(["r", "g", "b"], __read("getMainLed")); }
function getFrontLed() { return __obj(["r", "g", "b"], __read("getFrontLed")); }
function getBackLed() { return __obj(["r", "g", "b"], __read("getBackLed")); }
function getColorChannel(channel) {
  const c = __obj(["r", "g", "b"], __read("getColorChannel"));
  if (c === null) return null;
  const k = { red: "r", green: "g", blue: "b", 0: "r", 1: "g", 2: "b" }[String(channel).toLowerCase()] || String(channel).toLowerCase();
  if (!(k in c)) throw new RangeError("getColorChannel: the channel is \"r\", \"g\" or \"b\", not " + String(channel).slice(0, 40));
  return c[k];
}
function getCurrentTime() { return __read("getCurrentTime"); }
function getRandomFloat(min, max) {
  const lo = __num(min, "getRandomFloat: min"), hi = __num(max, "getRandomFloat: max");
  return Math.random() * (hi - lo) + lo;
}
function getLastIRMessage() { return __read("getLastIRMessage"); }
function getRandomInt(min, max) {
  const lo = __num(min, "getRandomInt: min"), hi = __num(max, "getRandomInt: max");
  return Math.floor(Math.random() * (hi - lo + 1)) + lo;
}
function getRandomColor() { return { r: getRandomInt(0, 255), g: getRandomInt(0, 255), b: getRandomInt(0, 255) }; }
function registerEvent(type, fn) {
  if (typeof fn !== "function") throw new TypeError("registerEvent: needs a function to call");
  return __on(String(type), fn);
}
const __api = {
  EventType,
  Stance,
  MatrixRotation,
  MatrixAnimationTransition,
  Sound,
  console,
  roll,
  rollDistance,
  rollToDistance,
  driveToDistance,
  setSpeed,
  setHeading,
  stopRoll,
  spin,
  rawMotor,
  setStabilization,
  resetAim,
  delay,
  exitProgram,
  setMainLed,
  setFrontLed,
  setBackLed,
  setLeftHeadlightLed,
  setRightHeadlightLed,
  setLeftLed,
  setRightLed,
  fade,
  strobe,
  setHoloProjectorLed,
  setLogicDisplayLeds,
  setDomeLeds,
  setDisplayImage,
  setMatrixCharacter,
  scrollMatrixText,
  drawMatrixPixel,
  drawMatrixLine,
  drawMatrixFill,
  clearMatrix,
  setMatrixRotation,
  registerMatrixAnimation,
  playMatrixAnimation,
  pauseMatrixAnimation,
  resumeMatrixAnimation,
  speak,
  playSound,
  playAnimation,
  setDomePosition,
  setStance,
  setWaddle,
  calibrateCompass,
  startIRBroadcast,
  stopIRBroadcast,
  startIRFollow,
  stopIRFollow,
  startIREvade,
  stopIREvade,
  sendIRMessage,
  listenForIRMessage,
  getLocation,
  getVelocity,
  getSpeed,
  getHeading,
  getOrientation,
  getAcceleration,
  getVerticalAcceleration,
  getGyroscope,
  getDistance,
  getElapsedTime,
  getLuminosity,
  getColor,
  getCompassDirection,
  getBatteryVoltage,
  getMainLed,
  getLastIRMessage,
  getFrontLed,
  getBackLed,
  getColorChannel,
  getCurrentTime,
  getRandomInt,
  getRandomFloat,
  getRandomColor,
  buildString,
  setTimeout,
  setInterval,
  clearTimeout,
  clearInterval,
  registerEvent,
};
for (const name of Object.keys(__api)) {
  Object.defineProperty(globalThis, name, { value: __api[name], writable: true, configurable: true, enumerable: false });
}
})
