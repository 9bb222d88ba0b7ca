"""Analysis of rendered images: regions and their statistics, targets, merits, masks."""
