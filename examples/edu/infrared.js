// Two robots greet each other in infrared.
// Models: bolt, boltplus, rvr (run it on two at once, each runs it)
//   droidctl examples infrared.js > infrared.js && droidctl run infrared.js --sim bolt,bolt
// Each turns red, listens on channel 3, says hello on it, and turns green when it hears the
// other (a robot does not hear itself). Alone, it hears nothing and ends red.
async function onIRMessage(channel) {
  setMainLed({ r: 0, g: 255, b: 0 });
  await speak("heard channel " + getLastIRMessage(), false);
}
registerEvent(EventType.onIRMessage, onIRMessage);

async function startProgram() {
  setMainLed({ r: 255, g: 0, b: 0 });
  listenForIRMessage([3]);
  // Give the other robot time to start listening too.
  await delay(2);
  sendIRMessage(3, 64);
  await delay(1);
  exitProgram();
}
