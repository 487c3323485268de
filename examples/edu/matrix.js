// BOLT's matrix: a letter, a drawing, scrolling text, and a spin to finish.
// Models: bolt, boltplus
//   droidctl examples matrix.js > matrix.js && droidctl run matrix.js --sim bolt
async function startProgram() {
  setMatrixCharacter("A", { r: 255, g: 0, b: 0 });
  await delay(1);
  clearMatrix();
  drawMatrixLine({ r: 0, g: 0, b: 255 }, { x: 0, y: 0 }, { x: 7, y: 0 });
  drawMatrixFill({ r: 0, g: 255, b: 0 }, { x: 2, y: 2 }, { x: 5, y: 5 });
  drawMatrixPixel({ r: 255, g: 255, b: 255 }, { x: 7, y: 7 });
  await delay(1);
  await scrollMatrixText("HI", { r: 255, g: 255, b: 0 }, 10, true);
  await spin(360, 1);
  setMatrixCharacter("Z", { r: 0, g: 255, b: 255 });
}
