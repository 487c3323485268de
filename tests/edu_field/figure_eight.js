// Models: bolt mini sprk
// A figure eight: arcs by spinning while rolling, then the motors driven raw.
async function startProgram() {
  setMainLed({ r: 0, g: 0, b: 255 });
  setSpeed(50);
  await spin(360, 2);
  setMainLed({ r: 255, g: 0, b: 255 });
  await spin(-360, 2);
  stopRoll();
  await delay(0.5);
  await rawMotor(80, 80, 0.8);
  await delay(0.5);
  setMainLed({ r: 255, g: 255, b: 255 });
  await delay(0.5);
}
