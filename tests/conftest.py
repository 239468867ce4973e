"""Shared pytest setup: a non-interactive matplotlib backend for study tests."""

import matplotlib

matplotlib.use("Agg")
