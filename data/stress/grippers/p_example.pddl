(define (problem grippers-p-example)
  (:domain gripper-strips)
  (:objects
    robot1 - robot
    room1 room2 room3 - room
    lgripper1 rgripper1 - gripper
    ball1 ball2 ball3 - object
  )
  (:init
    (at-robby robot1 room3)
    (free robot1 lgripper1)
    (free robot1 rgripper1)
    (at ball1 room1)
    (at ball2 room1)
    (at ball3 room1)
  )
  (:goal (and
    (at ball1 room3)
    (at ball2 room3)
    (at ball3 room3)
  ))
)
