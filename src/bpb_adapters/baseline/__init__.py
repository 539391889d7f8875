"""Offline baseline adapters that answer through the same parse path as real models."""
