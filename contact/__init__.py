"""Closed-form contact theory, the frictional contact solver against a rigid body, scenes and the reduced model."""

__all__: list[str] = []
