// A square: four one-second sides, a right turn and a new colour at each corner.
// Models: all but robi
//   droidctl examples square.js > square.js && droidctl run square.js --sim bolt
async function startProgram() {
  const colours = [
    { r: 255, g: 0, b: 0 },
    { r: 0, g: 255, b: 0 },
    { r: 0, g: 0, b: 255 },
    { r: 255, g: 255, b: 0 },
  ];
  for (let side = 0; side < 4; side++) {
    setMainLed(colours[side]);
    await roll(side * 90, 80, 1);
    await delay(0.5);
  }
  setMainLed({ r: 255, g: 255, b: 255 });
}
