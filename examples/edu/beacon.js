// A beacon for examples/edu/follow.js: this robot broadcasts on channels 0 (near) and 1 (far)
// and stays where it is, blue, for six seconds.
//   droidctl run examples/edu/beacon.js examples/edu/follow.js --sim bolt,bolt
async function startProgram() {
  setMainLed({ r: 0, g: 0, b: 255 });
  startIRBroadcast(0, 1);
  await delay(6);
  stopIRBroadcast();
}
