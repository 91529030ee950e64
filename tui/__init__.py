"""Textual terminal UI for the hands-free programming dialog."""
