"""Executing plans: simulator backends and episode set-up."""
