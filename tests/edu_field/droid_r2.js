// Models: r2d2 r2q5
// R2-D2 on patrol: its dome, its lights, there and back.
async function startProgram() {
  setHoloProjectorLed(255);
  setLogicDisplayLeds(128);
  setDomePosition(90);
  setFrontLed({ r: 0, g: 0, b: 255 });
  await roll(0, 80, 1.5);
  await delay(0.5);
  setDomePosition(-90);
  setBackLed({ r: 255, g: 0, b: 0 });
  await roll(180, 80, 1);
  setHoloProjectorLed(0);
  setDomePosition(0);
  await delay(1);
}
