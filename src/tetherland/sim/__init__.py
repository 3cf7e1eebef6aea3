"""MuJoCo simulation of the tethered quadrotor: scene, plant, hook, sensors, runner."""
