(define (problem grippers-p06)
  (:domain gripper-strips)
  (:objects
    robot1 robot2 - robot
    room1 room2 room3 - room
    lgripper1 rgripper1 lgripper2 rgripper2 - gripper
    ball1 - object
  )
  (:init
    (at-robby robot1 room2)
    (free robot1 lgripper1)
    (free robot1 rgripper1)
    (at-robby robot2 room1)
    (free robot2 lgripper2)
    (free robot2 rgripper2)
    (at ball1 room1)
  )
  (:goal (and
    (at ball1 room2)
  ))
)
