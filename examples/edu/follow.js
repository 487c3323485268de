// Follow the robot that runs examples/edu/beacon.js: look for a broadcaster on channels 0 and
// 1, roll up to it, and say how far that took.
//   droidctl run examples/edu/beacon.js examples/edu/follow.js --sim bolt,bolt
async function startProgram() {
  setMainLed({ r: 0, g: 255, b: 0 });
  startIRFollow(0, 1);
  await delay(5);
  stopIRFollow();
  await speak("followed " + Math.round(getDistance()) + " cm", false);
}
