(define (problem grippers-p02)
  (:domain gripper-strips)
  (:objects
    robot1 robot2 - robot
    room1 room2 room3 - room
    lgripper1 rgripper1 lgripper2 rgripper2 - gripper
    ball1 ball2 ball3 ball4 - object
  )
  (:init
    (at-robby robot1 room1)
    (free robot1 lgripper1)
    (free robot1 rgripper1)
    (at-robby robot2 room2)
    (free robot2 lgripper2)
    (free robot2 rgripper2)
    (at ball1 room2)
    (at ball2 room2)
    (at ball3 room3)
    (at ball4 room2)
  )
  (:goal (and
    (at ball1 room1)
    (at ball2 room3)
    (at ball3 room2)
    (at ball4 room3)
  ))
)
