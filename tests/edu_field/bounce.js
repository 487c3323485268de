// Models: bolt mini sprk bb8 r2d2
// Timeout: 8
// The usual collision handler, with no exitProgram: roll east to the wall, stop there, red,
// and face back the way it came. The program runs until it is stopped.
async function onCollision() {
  stopRoll();
  setMainLed({ r: 255, g: 0, b: 0 });
  setHeading(270);
}
registerEvent(EventType.onCollision, onCollision);

async function startProgram() {
  setMainLed({ r: 0, g: 255, b: 0 });
  setHeading(90);
  setSpeed(150);
}
