// Models: bolt mini sprk bb8 r2d2 rvr
// Lights in loops: a hexagon with a colour per side, then a fast blink that ends on green.
var colours = [
  { r: 255, g: 0, b: 0 },
  { r: 0, g: 255, b: 0 },
  { r: 0, g: 0, b: 255 },
];
async function startProgram() {
  for (var side = 0; side < 6; side++) {
    setMainLed(colours[side % 3]);
    await roll(side * 60, 50, 0.6);
  }
  await delay(0.5);
  for (var i = 0; i < 10; i++) {
    setMainLed(colours[i % 3]);
    await delay(0.1);
  }
  setMainLed(colours[1]);
  await delay(0.5);
}
