// Models: bolt mini sprk bb8 r2d2 rvr
// The sensors read on the first line, as Sphero's own examples do: the square starts where
// the robot faces.
async function startProgram() {
  var yaw = getOrientation().yaw;
  var accel = getAcceleration();
  var where = getLocation();
  var spin = getGyroscope().yaw;
  var moving = getVelocity();
  if (accel.z > 0.5 && where.x === 0 && moving.y === 0 && spin === 0) {
    setMainLed({ r: 0, g: 255, b: 0 });
  } else {
    setMainLed({ r: 255, g: 0, b: 0 });
  }
  var heading = Math.round(yaw);
  for (var side = 0; side < 4; side++) {
    await roll(heading + side * 90, 60, 1);
  }
  setMainLed({ r: 255, g: 255, b: 255 });
  await delay(1);
}
