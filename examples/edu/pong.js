// Pong: roll forward, turn around at each hit, and end after the third.
// Models: all but robi
//   droidctl examples pong.js > pong.js && droidctl run pong.js --sim bolt
let hits = 0;

async function onCollision() {
  hits += 1;
  stopRoll();
  setMainLed({ r: 255, g: 0, b: 0 });
  if (hits >= 3) {
    exitProgram();
    return;
  }
  await delay(0.5);
  setMainLed({ r: 0, g: 255, b: 0 });
  setHeading((getHeading() + 180) % 360);
  setSpeed(100);
}
registerEvent(EventType.onCollision, onCollision);

async function startProgram() {
  setMainLed({ r: 0, g: 255, b: 0 });
  setHeading(0);
  setSpeed(100);
}
