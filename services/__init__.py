"""The handsfree-pbd services, each its own process."""
