"""Eye tracking from the camera picture: pupil and glint segmentation, gaze estimation."""
