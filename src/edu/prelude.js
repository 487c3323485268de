// The Sphero Edu JavaScript API as programs see it: names, arguments and return shapes as
// Sphero documents them. Each call hands plain numbers and strings to droidctl (`__call`,
// `__read`, `__on`), which does the work on its own clock (src/edu/api.rs).
"use strict";
const EventType = Object.freeze({
  onCollision: "onCollision", onFreefall: "onFreefall", onLanding: "onLanding",
  onGyroMax: "onGyroMax", onCharging: "onCharging", onNotCharging: "onNotCharging",
  onIRMessage: "onIRMessage", onColor: "onColor",
});
const Stance = Object.freeze({ Bipod: "twolegs", Tripod: "threelegs" });
const MatrixRotation = Object.freeze({ Deg0: 0, Deg90: 90, Deg180: 180, Deg270: 270 });
const MatrixAnimationTransition = Object.freeze({ None: "none", Fade: "fade" });
function __num(v, what) {
  const n = Number(v);
  if (!Number.isFinite(n)) throw new TypeError(what + " must be a number, not " + String(v));
  return n;
}
function __rgb(c, what) {
  if (c === null || typeof c !== "object") throw new TypeError((what || "color") + " must be a color like { r: 255, g: 0, b: 0 }");
  const ch = (v) => Math.max(0, Math.min(255, Math.round(Number(v) || 0)));
  return [ch(c.r), ch(c.g), ch(c.b)];
}
function __xy(p, what) {
  if (p === null || typeof p !== "object") throw new TypeError(what + " must be a point like { x: 0, y: 0 }");
  return [__num(p.x, what + ".x"), __num(p.y, what + ".y")];
}
function __obj(keys, a) { if (!a) return null; const o = {}; keys.forEach((k, i) => { o[k] = a[i]; }); return o; }
function roll(heading, speed, duration) { return __call("roll", __num(heading, "heading"), __num(speed, "speed"), __num(duration, "duration")); }
function rollDistance(heading, speed, distance) { return __call("rollDistance", __num(heading, "heading"), __num(speed, "speed"), __num(distance, "distance")); }
function setSpeed(speed) { return __call("setSpeed", __num(speed, "speed")); }
function setHeading(heading) { return __call("setHeading", __num(heading, "heading")); }
function stopRoll(heading) { return heading === undefined ? __call("stopRoll") : __call("stopRoll", __num(heading, "heading")); }
function spin(degrees, duration) { return __call("spin", __num(degrees, "degrees"), __num(duration, "duration")); }
function rawMotor(left, right, duration) { return __call("rawMotor", __num(left, "left"), __num(right, "right"), duration === undefined ? -1 : __num(duration, "duration")); }
function setStabilization(on) { return __call("setStabilization", on ? 1 : 0); }
function resetAim() { return __call("resetAim"); }
function delay(seconds) { return __call("delay", __num(seconds, "seconds")); }
function exitProgram() { return __call("exitProgram"); }
function setMainLed(color) { return __call("setMainLed", ...__rgb(color)); }
function setFrontLed(color) { return __call("setFrontLed", ...__rgb(color)); }
function setBackLed(color) {
  if (typeof color === "number") return __call("setBackLedBrightness", __num(color, "brightness"));
  return __call("setBackLed", ...__rgb(color));
}
function fade(from, to, duration) { return __call("fade", ...__rgb(from, "fromColor"), ...__rgb(to, "toColor"), __num(duration, "duration")); }
function strobe(color, period, count) { return __call("strobe", ...__rgb(color), __num(period, "period"), __num(count, "count")); }
function setHoloProjectorLed(b) { return __call("setHoloProjectorLed", __num(b, "brightness")); }
function setLogicDisplayLeds(b) { return __call("setLogicDisplayLeds", __num(b, "brightness")); }
function setDomeLeds(b) { return __call("setDomeLeds", __num(b, "brightness")); }
function setMatrixCharacter(character, color) { return __call("setMatrixCharacter", String(character), ...__rgb(color)); }
function scrollMatrixText(text, color, fps, wait) { return __call("scrollMatrixText", String(text), ...__rgb(color), fps === undefined ? 10 : __num(fps, "fps"), wait === false ? 0 : 1); }
function drawMatrixPixel(color, p) { return __call("drawMatrixPixel", ...__rgb(color), ...__xy(p, "point")); }
function drawMatrixLine(color, a, b) { return __call("drawMatrixLine", ...__rgb(color), ...__xy(a, "start"), ...__xy(b, "end")); }
function drawMatrixFill(color, a, b) { return __call("drawMatrixFill", ...__rgb(color), ...__xy(a, "start"), ...__xy(b, "end")); }
function clearMatrix() { return __call("clearMatrix"); }
function setMatrixRotation(degrees) { return __call("setMatrixRotation", __num(degrees, "degrees")); }
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
      row.forEach((v) => flat.push(__num(v, "a pixel")));
    });
  });
  const colours = [];
  palette.forEach((c) => colours.push(...__rgb(c, "a palette color")));
  const fade = a.transition === MatrixAnimationTransition.Fade ? 1 : 0;
  __call(what, a.fps === undefined ? 10 : __num(a.fps, "fps"), fade, palette.length, ...colours, frames.length, ...flat);
  return __animations++;
}
function playMatrixAnimation(index, loop) { return __call("playMatrixAnimation", __num(index, "index"), loop === false ? 0 : 1); }
function pauseMatrixAnimation() { return __call("pauseMatrixAnimation"); }
function resumeMatrixAnimation() { return __call("resumeMatrixAnimation"); }
function speak(text, wait) { return __call("speak", String(text), wait ? 1 : 0); }
function playSound(sound, wait) { return __call("playSound", String(sound), wait ? 1 : 0); }
function playAnimation(animation) { return __call("playAnimation", __num(animation, "animation")); }
function setDomePosition(degrees) { return __call("setDomePosition", __num(degrees, "degrees")); }
function setStance(stance) { return __call("setStance", stance === Stance.Bipod || stance === "bipod" ? 2 : 3); }
function setWaddle(on) { return __call("setWaddle", on ? 1 : 0); }
function calibrateCompass() { return __call("calibrateCompass"); }
function startIRBroadcast(near, far) { return __call("startIRBroadcast", __num(near, "near"), __num(far, "far")); }
function stopIRBroadcast() { return __call("stopIRBroadcast"); }
function startIRFollow(near, far) { return __call("startIRFollow", __num(near, "near"), __num(far, "far")); }
function stopIRFollow() { return __call("stopIRFollow"); }
function startIREvade(near, far) { return __call("startIREvade", __num(near, "near"), __num(far, "far")); }
function stopIREvade() { return __call("stopIREvade"); }
function sendIRMessage(channel, intensity) { return __call("sendIRMessage", __num(channel, "channel"), __num(intensity, "intensity")); }
function listenForIRMessage(channels) {
  const list = Array.isArray(channels) ? channels : [channels];
  return __call("listenForIRMessage", ...list.map((c) => __num(c, "channel")));
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
function getLastIRMessage() { return __read("getLastIRMessage"); }
function getRandomInt(min, max) { return Math.floor(Math.random() * (max - min + 1)) + min; }
function getRandomColor() { return { r: getRandomInt(0, 255), g: getRandomInt(0, 255), b: getRandomInt(0, 255) }; }
function registerEvent(type, fn) {
  if (typeof fn !== "function") throw new TypeError("registerEvent needs a function to call");
  return __on(String(type), fn);
}
