// A square: four sides of one second each, turning right at each corner, a new colour on
// each side. Run it with `droidctl run examples/edu/square.js --sim bolt`.
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
