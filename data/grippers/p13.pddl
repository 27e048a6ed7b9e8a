(define (problem grippers-p13)
  (:domain gripper-strips)
  (:objects
    robot1 - robot
    room1 room2 room3 - room
    lgripper1 rgripper1 - gripper
    ball1 ball2 - object
  )
  (:init
    (at-robby robot1 room3)
    (free robot1 lgripper1)
    (free robot1 rgripper1)
    (at ball1 room3)
    (at ball2 room2)
  )
  (:goal (and
    (at ball1 room2)
    (at ball2 room3)
  ))
)
