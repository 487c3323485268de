// Models: rvr
// RVR's own lights while it drives an L: colour read first, headlights, side lights,
// brake lights.
async function startProgram() {
  var floor = getColor();
  setLeftHeadlightLed({ r: floor.r, g: floor.g, b: floor.b });
  setRightHeadlightLed({ r: 255, g: 255, b: 255 });
  setLeftLed({ r: 255, g: 0, b: 0 });
  setRightLed({ r: 0, g: 255, b: 0 });
  await roll(0, 100, 1.5);
  setBackLed({ r: 255, g: 0, b: 0 });
  await roll(90, 100, 1);
  setLeftLed({ r: 0, g: 0, b: 255 });
  await delay(1);
}
