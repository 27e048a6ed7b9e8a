(define (problem blocksworld-p02)
  (:domain blocksworld)
  (:objects
    b1 b2 b3 - block
  )
  (:init
    (on-table b1)
    (on b2 b1)
    (on b3 b2)
    (clear b3)
    (arm-empty)
  )
  (:goal (and
    (on b1 b2)
    (on b2 b3)
  ))
)
