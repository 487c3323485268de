// Models: bolt mini bb8 sprk
// An un-awaited helper: the lights flash while the robot rolls there and back.
async function flash() {
  for (var i = 0; i < 4; i++) {
    setMainLed({ r: 255, g: 128, b: 0 });
    await delay(0.25);
    setMainLed({ r: 0, g: 0, b: 0 });
    await delay(0.25);
  }
  setBackLed({ r: 0, g: 0, b: 255 });
}
async function startProgram() {
  flash();
  await roll(0, 70, 1.5);
  await roll(180, 70, 1);
  await delay(1);
}
