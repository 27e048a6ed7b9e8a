(define (problem grippers-p07)
  (:domain gripper-strips)
  (:objects
    robot1 robot2 robot3 - robot
    room1 room2 room3 room4 - room
    lgripper1 rgripper1 lgripper2 rgripper2 lgripper3 rgripper3 - gripper
    ball1 ball2 ball3 - object
  )
  (:init
    (at-robby robot1 room2)
    (free robot1 lgripper1)
    (free robot1 rgripper1)
    (at-robby robot2 room2)
    (free robot2 lgripper2)
    (free robot2 rgripper2)
    (at-robby robot3 room2)
    (free robot3 lgripper3)
    (free robot3 rgripper3)
    (at ball1 room2)
    (at ball2 room2)
    (at ball3 room4)
  )
  (:goal (and
    (at ball1 room4)
    (at ball2 room4)
    (at ball3 room2)
  ))
)
