// Follow the robot that runs beacon.js: find it on infrared, roll up to it, say how far.
// Models: bolt, boltplus, rvr (with beacon.js on a second robot)
//   droidctl run beacon.js follow.js --sim bolt,bolt
// It looks for a broadcaster on channels 0 and 1.
async function startProgram() {
  setMainLed({ r: 0, g: 255, b: 0 });
  startIRFollow(0, 1);
  await delay(5);
  stopIRFollow();
  await speak("followed " + Math.round(getDistance()) + " cm", false);
}
