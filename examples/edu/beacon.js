// A beacon for follow.js: broadcast on infrared channels 0 (near) and 1 (far), stay, blue.
// Models: bolt, boltplus, rvr (with follow.js on a second robot)
//   droidctl run beacon.js follow.js --sim bolt,bolt
// This robot stays where it is for six seconds.
async function startProgram() {
  setMainLed({ r: 0, g: 0, b: 255 });
  startIRBroadcast(0, 1);
  await delay(6);
  stopIRBroadcast();
}
