"""Sensor array model, slip estimator, grasp-force control and actuator control with a disturbance observer."""

__all__: list[str] = []
