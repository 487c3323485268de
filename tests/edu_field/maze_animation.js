// Models: bolt
// A maze run as students write it: register an animation, play it, draw, roll, end on a
// character.
var arrow = [
  [0, 0, 0, 1, 1, 0, 0, 0],
  [0, 0, 1, 1, 1, 1, 0, 0],
  [0, 1, 0, 1, 1, 0, 1, 0],
  [1, 0, 0, 1, 1, 0, 0, 1],
  [0, 0, 0, 1, 1, 0, 0, 0],
  [0, 0, 0, 1, 1, 0, 0, 0],
  [0, 0, 0, 1, 1, 0, 0, 0],
  [0, 0, 0, 2, 2, 0, 0, 0],
];
var blank = [
  [0, 0, 0, 0, 0, 0, 0, 0],
  [0, 0, 0, 0, 0, 0, 0, 0],
  [0, 0, 0, 0, 0, 0, 0, 0],
  [0, 0, 0, 2, 2, 0, 0, 0],
  [0, 0, 0, 2, 2, 0, 0, 0],
  [0, 0, 0, 0, 0, 0, 0, 0],
  [0, 0, 0, 0, 0, 0, 0, 0],
  [0, 0, 0, 0, 0, 0, 0, 0],
];
async function startProgram() {
  registerMatrixAnimation({
    frames: [arrow, blank, arrow],
    palette: [{ r: 0, g: 0, b: 0 }, { r: 255, g: 255, b: 0 }, { r: 0, g: 128, b: 255 }],
    fps: 4,
    transition: MatrixAnimationTransition.None,
  });
  playMatrixAnimation(0, false);
  await roll(0, 70, 1);
  await delay(0.5);
  drawMatrixLine({ r: 255, g: 0, b: 0 }, { x: 0, y: 0 }, { x: 7, y: 0 });
  drawMatrixPixel({ r: 0, g: 255, b: 0 }, { x: 3, y: 4 });
  await roll(90, 70, 1);
  drawMatrixFill({ r: 0, g: 0, b: 255 }, { x: 5, y: 5 }, { x: 7, y: 7 });
  setFrontLed({ r: 255, g: 255, b: 0 });
  setBackLed({ r: 255, g: 0, b: 0 });
  await delay(0.5);
}
