// Models: bolt mini sprk r2d2
// Sounds between the moves: waited ones hold the program for their length.
async function startProgram() {
  await Sound.Animal.Cat.play(true);
  await roll(90, 80, 1);
  Sound.Effects.play(false);
  await roll(270, 80, 0.5);
  await Sound.play(true);
  setMainLed({ r: 255, g: 0, b: 255 });
  await speak("all done", false);
  await delay(0.5);
}
