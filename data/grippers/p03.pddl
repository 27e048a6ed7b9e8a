(define (problem grippers-p03)
  (:domain gripper-strips)
  (:objects
    robot1 robot2 - robot
    room1 room2 room3 room4 room5 - room
    lgripper1 rgripper1 lgripper2 rgripper2 - gripper
    ball1 ball2 - object
  )
  (:init
    (at-robby robot1 room4)
    (free robot1 lgripper1)
    (free robot1 rgripper1)
    (at-robby robot2 room3)
    (free robot2 lgripper2)
    (free robot2 rgripper2)
    (at ball1 room2)
    (at ball2 room5)
  )
  (:goal (and
    (at ball1 room4)
    (at ball2 room4)
  ))
)
