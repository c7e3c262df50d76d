"""The world families: each package holds a scene, its world (where truth lives), the robot with its
own sensors and perception, the tasks set in it (one file each) and their scorers."""
