"""Scene description: validated, typed, unit-bearing data. No physics, no tracing."""
