"""Scenes shipped with eyelume (TOML) and their data files."""
